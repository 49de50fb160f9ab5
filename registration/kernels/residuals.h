// The one per-pixel entry point of every registration method: evaluates method p.method at pixel (x, y) and
// writes 0..HF_REG_MAX_ROWS rows. Common C++/OpenCL-C subset; the CPU backend and the OpenCL reduction kernel
// both call only this function, then hf_reg_accumulate() for each row written.
//
// Combined ICP (report eq. 47-48): the geometric row and the photometric row of the same pixel, the photometric one
// weighted by lambda = p.rgb_weight (scaling J and r of a row by sqrt(lambda) is the same as weighting it by
// lambda; eq. 48's sqrt(lambda) on J^T r alone would be inconsistent with its lambda on J^T J).
//
// Pointers a method does not read may be any valid buffer (the OpenCL side binds a dummy): icp reads
// cur_vertices, cur_normals, ref_vertices, ref_normals; photometric reads cur_vertices, cur_intensity,
// ref_intensity, ref_grad_x, ref_grad_y (and ref_vertices with occlusion_check); combined reads all.
#ifndef HF_REGISTRATION_KERNELS_RESIDUALS_H
#define HF_REGISTRATION_KERNELS_RESIDUALS_H

#include "registration/kernels/icp_kernel.h"
#include "registration/kernels/photometric_kernel.h"

HF_INLINE int hf_reg_pixel(int x, int y, const HF_GLOBAL hf_float4* cur_vertices,
                           const HF_GLOBAL hf_float4* cur_normals, const HF_GLOBAL float* cur_intensity,
                           const HF_GLOBAL hf_float4* ref_vertices, const HF_GLOBAL hf_float4* ref_normals,
                           const HF_GLOBAL float* ref_intensity, const HF_GLOBAL float* ref_grad_x,
                           const HF_GLOBAL float* ref_grad_y, hf_intrinsics K, hf_transform12 T, hf_reg_params p,
                           hf_reg_row* rows) {
  int n = 0;
  if (p.method == HF_REG_ICP || p.method == HF_REG_COMBINED) {
    n += hf_icp_pixel(x, y, cur_vertices, cur_normals, ref_vertices, ref_normals, K, T, p, rows + n);
  }
  const int on_grid = p.photometric_step <= 1 || ((x % p.photometric_step) == 0 && (y % p.photometric_step) == 0);
  if ((p.method == HF_REG_PHOTOMETRIC || p.method == HF_REG_COMBINED) && on_grid) {
    n += hf_photometric_pixel(x, y, cur_vertices, cur_intensity, ref_vertices, ref_intensity, ref_grad_x,
                              ref_grad_y, K, T, p, rows + n);
  }
  return n;
}

// Convenience for a reduction over pixels: evaluates pixel (x, y) and adds its rows to sums.
HF_INLINE void hf_reg_accumulate_pixel(int x, int y, const HF_GLOBAL hf_float4* cur_vertices,
                                       const HF_GLOBAL hf_float4* cur_normals, const HF_GLOBAL float* cur_intensity,
                                       const HF_GLOBAL hf_float4* ref_vertices,
                                       const HF_GLOBAL hf_float4* ref_normals, const HF_GLOBAL float* ref_intensity,
                                       const HF_GLOBAL float* ref_grad_x, const HF_GLOBAL float* ref_grad_y,
                                       hf_intrinsics K, hf_transform12 T, hf_reg_params p, hf_reg_sum_t* sums) {
  hf_reg_row rows[HF_REG_MAX_ROWS];
  const int n = hf_reg_pixel(x, y, cur_vertices, cur_normals, cur_intensity, ref_vertices, ref_normals,
                             ref_intensity, ref_grad_x, ref_grad_y, K, T, p, rows);
  for (int k = 0; k < n; ++k) hf_reg_accumulate(&rows[k], sums);
}

#endif
