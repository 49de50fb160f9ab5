// The C++ reduction backend ("cpu"): the per-pixel rows of registration/kernels/residuals.h summed in double.
//
// Deterministic: the image is cut into fixed chunks of rows_per_chunk rows; each chunk is summed in double in
// pixel order (by whichever TBB thread runs it) and the chunk sums are added in chunk order, so the result does
// not depend on the number of threads or on scheduling.
#pragma once

#include <vector>

#include "registration/reduction.h"

namespace hf {

class CpuReductionBackend final : public ReductionBackend {
 public:
  explicit CpuReductionBackend(int rows_per_chunk = 8);
  NormalEquations reduce(const ResidualProblem& problem) override;
  std::string name() const override { return "cpu"; }

 private:
  int rows_per_chunk_;
  std::vector<double> chunk_sums_;  // reused between calls
};

}  // namespace hf
