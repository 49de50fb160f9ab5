// The C++ reduction backend ("cpu"): the per-pixel rows of the problem's kernel (DenseKernel::rows) summed in double.
//
// Deterministic: the image is cut into fixed chunks of rows_per_chunk rows; each chunk is summed in double in
// pixel order (by whichever TBB thread runs it) and the chunk sums are added in chunk order, so the result does
// not depend on the number of threads or on scheduling.
//
// On processors with AVX2, a kernel with an eight-lane spelling (DenseKernel::rows_avx2, e.g.
// registration/cpu_backend_avx2.h) is evaluated eight pixels at a time: the same rows, summed per lane and then
// across lanes, so the sums differ from the pixel-by-pixel loop only by the order of the double additions. A kernel
// without one runs its pixel loop (never zero rows). vectorised = false forces the pixel-by-pixel loop for every
// kernel (tests compare the two).
#pragma once

#include <vector>

#include "registration/reduction.h"

namespace hf {

class CpuReductionBackend final : public ReductionBackend {
 public:
  explicit CpuReductionBackend(int rows_per_chunk = 8, bool vectorised = true);
  NormalEquations reduce(const ResidualProblem& problem) override;
  std::string name() const override { return "cpu"; }
  bool vectorised() const { return vectorised_; }  // whether reduce() may run AVX2 paths
  bool vectorises(const DenseKernel& kernel) const;  // whether reduce() runs kernel's AVX2 path

 private:
  int rows_per_chunk_;
  bool vectorised_;
  std::vector<double> chunk_sums_;  // reused between calls
};

}  // namespace hf
