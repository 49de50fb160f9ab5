// Compiled by CTest (registration_kernels_opencl_c12) with clang -x cl -cl-std=CL1.2 -fsyntax-only, so the shared
// registration kernel headers are checked as real OpenCL C, not only as C++.
#include "registration/kernels/residuals.h"

__kernel void check_reg_pixel(__global const hf_float4* cv, __global const hf_float4* cn, __global const float* ci,
                              __global const hf_float4* rv, __global const hf_float4* rn, __global const float* ri,
                              __global const float* gx, __global const float* gy, hf_intrinsics K,
                              hf_transform12 T, hf_reg_params p, __global float* out) {
  const int x = get_global_id(0), y = get_global_id(1);
  hf_reg_sum_t sums[HF_REG_SUMS];
  for (int k = 0; k < HF_REG_SUMS; ++k) sums[k] = 0.0f;
  hf_reg_accumulate_pixel(x, y, cv, cn, ci, rv, rn, ri, gx, gy, K, T, p, sums);
  for (int k = 0; k < HF_REG_SUMS; ++k) out[(y * K.width + x) * HF_REG_SUMS + k] = sums[k];
}
