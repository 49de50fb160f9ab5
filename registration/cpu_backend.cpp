#include "registration/cpu_backend.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/error.h"
#include "core/simd_avx2.h"

namespace hf {

CpuReductionBackend::CpuReductionBackend(int rows_per_chunk, bool vectorised)
    : rows_per_chunk_(std::max(1, rows_per_chunk)), vectorised_(vectorised && cpu_has_avx2()) {}

NormalEquations CpuReductionBackend::reduce(const ResidualProblem& problem) {
  validate_problem(problem);
  const int height = problem.height();
  const int chunks = (height + rows_per_chunk_ - 1) / rows_per_chunk_;
  chunk_sums_.assign(size_t(chunks) * HF_REG_SUMS, 0.0);
  // A method without an eight-lane spelling runs its scalar loop here: never no rows.
  const RowsFunction rows =
      vectorised_ && problem.kernel->rows_avx2 != nullptr ? problem.kernel->rows_avx2 : problem.kernel->rows;
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks), [&](const tbb::blocked_range<int>& range) {
    for (int c = range.begin(); c != range.end(); ++c) {
      const int y0 = c * rows_per_chunk_, y1 = std::min(height, y0 + rows_per_chunk_);
      rows(problem, y0, y1, chunk_sums_.data() + size_t(c) * HF_REG_SUMS);
    }
  });
  double total[HF_REG_SUMS] = {};
  for (int c = 0; c < chunks; ++c) {
    const double* sums = chunk_sums_.data() + size_t(c) * HF_REG_SUMS;
    for (int k = 0; k < HF_REG_SUMS; ++k) total[k] += sums[k];
  }
  return NormalEquations::from_sums(total);
}

bool CpuReductionBackend::vectorises(const DenseKernel& kernel) const {
  return vectorised_ && kernel.rows_avx2 != nullptr;
}

}  // namespace hf
