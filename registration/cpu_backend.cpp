#include "registration/cpu_backend.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/kernels/residuals.h"

namespace hf {

CpuReductionBackend::CpuReductionBackend(int rows_per_chunk, bool vectorised)
    : rows_per_chunk_(std::max(1, rows_per_chunk)), vectorised_(vectorised && cpu_has_avx2()) {}

NormalEquations CpuReductionBackend::reduce(const ResidualProblem& problem) {
  validate_problem(problem);
  const int height = problem.height(), width = problem.width();
  const int chunks = (height + rows_per_chunk_ - 1) / rows_per_chunk_;
  chunk_sums_.assign(size_t(chunks) * HF_REG_SUMS, 0.0);
  const ResidualProblem& p = problem;
  const int step = p.params.method == HF_REG_PHOTOMETRIC ? std::max(1, p.params.photometric_step) : 1;
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks), [&](const tbb::blocked_range<int>& range) {
    for (int c = range.begin(); c != range.end(); ++c) {
      double* sums = chunk_sums_.data() + size_t(c) * HF_REG_SUMS;
      const int y0 = c * rows_per_chunk_, y1 = std::min(height, y0 + rows_per_chunk_);
      if (vectorised_) {
        detail::accumulate_rows_avx2(p, y0, y1, sums);
        continue;
      }
      // Photometric pixels off the photometric_step grid give no rows (hf_reg_pixel); skipping them here only
      // saves the calls.
      for (int y = y0; y < y1; ++y) {
        if (y % step != 0) continue;
        for (int x = 0; x < width; x += step) {
          hf_reg_accumulate_pixel(x, y, p.cur_vertices, p.cur_normals, p.cur_intensity, p.ref_vertices,
                                  p.ref_normals, p.ref_intensity, p.ref_grad_x, p.ref_grad_y, p.camera,
                                  p.T_ref_cur, p.params, sums);
        }
      }
    }
  });
  double total[HF_REG_SUMS] = {};
  for (int c = 0; c < chunks; ++c) {
    const double* sums = chunk_sums_.data() + size_t(c) * HF_REG_SUMS;
    for (int k = 0; k < HF_REG_SUMS; ++k) total[k] += sums[k];
  }
  return NormalEquations::from_sums(total);
}

}  // namespace hf
