// The eight-pixels-at-a-time spellings (AVX2) of the built-in kernels, the DenseKernel::rows_avx2 of icp,
// photometric and combined; the "cpu" backend runs them when the processor has AVX2.
//
// The per-pixel maths is registration/kernels/icp_kernel.h and photometric_kernel.h, evaluated for eight pixels
// at once with the same operations in the same order (no fused multiply-add), so every row equals the scalar
// kernel's row bit for bit; only the order of the double sums differs. tests/registration/test_reduction.cpp holds
// every registered kernel's two paths to each other. The scalar kernel stays the specification: change it first,
// then this file. A kernel without an entry here runs its scalar loop.
#pragma once

#include "core/simd_avx2.h"
#include "registration/reduction.h"

namespace hf::detail {

// Each adds the rows of current-frame pixel rows [y_begin, y_end) of `problem` to sums (HF_REG_SUMS doubles, the
// order of registration/kernels/reg_common.h), exactly the rows its kernel's pixel function writes: combined the
// geometric rows of every pixel, then the photometric rows of the pixels on the photometric step grid. problem.params
// is the kernel's parameter struct. Only call them when hf::cpu_has_avx2().
void icp_rows_avx2(const ResidualProblem& problem, int y_begin, int y_end, double* sums);
void photometric_rows_avx2(const ResidualProblem& problem, int y_begin, int y_end, double* sums);
void combined_rows_avx2(const ResidualProblem& problem, int y_begin, int y_end, double* sums);

}  // namespace hf::detail
