// The "cpu" backend's eight-pixels-at-a-time path (AVX2), used when the processor has AVX2.
//
// The per-pixel maths is registration/kernels/icp_kernel.h and photometric_kernel.h, evaluated for eight pixels
// at once with the same operations in the same order (no fused multiply-add), so every row equals the scalar
// kernel's row bit for bit; only the order of the double sums differs. tests/registration/test_reduction.cpp holds
// the two paths to each other. The scalar kernel stays the specification: change it first, then this file.
#pragma once

#include "core/simd_avx2.h"
#include "registration/reduction.h"

namespace hf::detail {

// Adds the rows of current-frame pixel rows [y_begin, y_end) of `problem` to sums (HF_REG_SUMS doubles, the
// order of registration/kernels/reg_common.h): the geometric rows of every pixel, then the photometric rows of
// the pixels on the photometric_step grid, exactly the rows hf_reg_pixel() writes. Only call it when
// hf::cpu_has_avx2().
void accumulate_rows_avx2(const ResidualProblem& problem, int y_begin, int y_end, double* sums);

}  // namespace hf::detail
