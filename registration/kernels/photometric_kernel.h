// Photometric ICP (dense intensity alignment, Steinbruecker 2011 / Kerl 2013), one pixel (report eq. 27-46).
// Common C++/OpenCL-C subset.
//
// Frame-to-frame on intensity: the current pixel's vertex (from the current depth) is warped into the reference
// camera, w = Pi(K T_ref_cur v_cur) (eq. 28), and the residual is r = I_ref(w) - I_cur(p) (eq. 31) with bilinear
// sampling. The Jacobian is the chain rule of eq. 34-45: a = grad I_ref(w) dPi/dv (eq. 36-37 with K folded in),
// J = a^T [ [-v]x I ]. Pixels are skipped when the vertex is invalid, behind the camera, warped outside the image
// (all bilinear taps must be inside), when the reference gradient is below min_gradient_sq, or (occlusion_check)
// when the reference vertex at the nearest pixel is valid and more than max_dist_m away in depth.
#ifndef HF_REGISTRATION_KERNELS_PHOTOMETRIC_KERNEL_H
#define HF_REGISTRATION_KERNELS_PHOTOMETRIC_KERNEL_H

#include "registration/kernels/reg_common.h"

// Returns 1 and fills *row when pixel (x, y) of the current frame yields a photometric residual, else 0.
// Intensities in [0, 1], gradients in intensity units per pixel (core/filters.h image_gradients). ref_vertices is
// read only when p.occlusion_check is non-zero.
HF_INLINE int hf_photometric_pixel(int x, int y, const HF_GLOBAL hf_float4* cur_vertices,
                                   const HF_GLOBAL float* cur_intensity, const HF_GLOBAL hf_float4* ref_vertices,
                                   const HF_GLOBAL float* ref_intensity, const HF_GLOBAL float* ref_grad_x,
                                   const HF_GLOBAL float* ref_grad_y, hf_intrinsics K, hf_transform12 T,
                                   hf_reg_params p, hf_reg_row* row) {
  const int idx = y * K.width + x;
  const hf_float4 vc = cur_vertices[idx];
  if (!hf_is_valid4(vc)) return 0;
  const hf_float4 v = hf_reg_transform_point(T, vc);
  if (!(v.z > 0.0f)) return 0;
  float px, py;
  hf_project(K, v, &px, &py);
  float i_ref, gx, gy;
  if (!hf_sample_bilinear(ref_intensity, K.width, K.height, px, py, 0, &i_ref)) return 0;
  hf_sample_bilinear(ref_grad_x, K.width, K.height, px, py, 0, &gx);
  hf_sample_bilinear(ref_grad_y, K.width, K.height, px, py, 0, &gy);
  if (!(gx * gx + gy * gy >= p.min_gradient_sq)) return 0;
  if (p.occlusion_check) {
    const int u = (int)(px + 0.5f), w = (int)(py + 0.5f);
    const hf_float4 vr = ref_vertices[w * K.width + u];
    if (hf_is_valid4(vr) && hf_fabs(vr.z - v.z) > p.max_dist_m) return 0;
  }
  const float r = i_ref - cur_intensity[idx];
  const float inv_z = 1.0f / v.z;
  const float ax = gx * K.fx * inv_z;
  const float ay = gy * K.fy * inv_z;
  const hf_float4 a = hf_make_float4(ax, ay, -(ax * v.x + ay * v.y) * inv_z, 0.0f);
  const float weight = p.rgb_weight * hf_reg_robust_weight(p.robust_rgb, r, p.scale_rgb, p.t_dof);
  hf_reg_set_row(v, a, r, weight, row);
  return 1;
}

#endif
