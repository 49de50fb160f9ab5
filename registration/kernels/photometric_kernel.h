// Photometric ICP (dense intensity alignment, Steinbruecker 2011 / Kerl 2013), one pixel (report eq. 27-46).
// Common C++/OpenCL-C subset.
//
// Frame-to-frame on intensity: the current pixel's vertex (from the current depth) is warped into the reference
// camera, w = Pi(K T_ref_cur v_cur) (eq. 28), and the residual is r = I_ref(w) - I_cur(p) (eq. 31) with bilinear
// sampling, or r = I_ref(w) - gain I_cur(p) where the exposure changed (DSO's brightness transfer without its offset;
// the gain is estimated per level before the iterations, registration/photometric.h). The Jacobian is the chain
// rule of eq. 34-45: a = grad I_ref(w) dPi/dv (eq. 36-37 with K folded in),
// J = a^T [ [-v]x I ]. Pixels are skipped when they are off the step grid, the vertex is invalid, behind the
// camera, warped outside the image (all bilinear taps must be inside), when the reference gradient is below
// min_gradient_sq, or (occlusion_check) when the reference vertex at the nearest pixel is valid and more than
// occlusion_max_depth_m away in depth.
// Reads HF_REG_IN_CUR_VERTICES, HF_REG_IN_CUR_INTENSITY, HF_REG_IN_REF_INTENSITY, HF_REG_IN_REF_GRAD_X/_Y and
// (occlusion_check) HF_REG_IN_REF_VERTICES.
#ifndef HF_REGISTRATION_KERNELS_PHOTOMETRIC_KERNEL_H
#define HF_REGISTRATION_KERNELS_PHOTOMETRIC_KERNEL_H

#include "registration/kernels/reg_common.h"

typedef struct {
  float weight;                // term weight lambda of the rows (eq. 47-48; 1 alone)
  hf_reg_robust robust;        // scale in intensity units ([0, 1])
  float min_gradient_sq;       // skip pixels whose reference gradient |grad I|^2 is below this
  int occlusion_check;         // non-zero rejects pixels whose warped depth differs from the reference vertex at
                               // that pixel by more than occlusion_max_depth_m
  float occlusion_max_depth_m;
  int step;                    // rows only for current pixels with x and y multiples of this (<= 1: every pixel)
  float gain;                  // brightness gain of the current frame (r = I_ref(w) - gain I_cur); 1: constancy
} hf_photometric_params;

// Returns 1 and fills *row when pixel (x, y) of the current frame yields a photometric residual, else 0.
// Intensities in [0, 1], gradients in intensity units per pixel (core/filters.h image_gradients).
HF_INLINE int hf_photometric_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                                   hf_photometric_params p, hf_reg_row* row) {
  if (p.step > 1 && ((x % p.step) != 0 || (y % p.step) != 0)) return 0;
  const int idx = y * K.width + x;
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[idx];
  if (!hf_is_valid4(vc)) return 0;
  const hf_float4 v = hf_reg_transform_point(T, vc);
  if (!(v.z > 0.0f)) return 0;
  float px, py;
  hf_project(K, v, &px, &py);
  float i_ref, gx, gy;
  if (!hf_sample_bilinear(maps->map[HF_REG_IN_REF_INTENSITY], K.width, K.height, px, py, 0, &i_ref)) return 0;
  hf_sample_bilinear(maps->map[HF_REG_IN_REF_GRAD_X], K.width, K.height, px, py, 0, &gx);
  hf_sample_bilinear(maps->map[HF_REG_IN_REF_GRAD_Y], K.width, K.height, px, py, 0, &gy);
  if (!(gx * gx + gy * gy >= p.min_gradient_sq)) return 0;
  if (p.occlusion_check) {
    const int u = (int)(px + 0.5f), w = (int)(py + 0.5f);
    const hf_float4 vr = hf_reg_map4(maps, HF_REG_IN_REF_VERTICES)[w * K.width + u];
    if (hf_is_valid4(vr) && hf_fabs(vr.z - v.z) > p.occlusion_max_depth_m) return 0;
  }
  const float r = i_ref - p.gain * maps->map[HF_REG_IN_CUR_INTENSITY][idx];
  const float inv_z = 1.0f / v.z;
  const float ax = gx * K.fx * inv_z;
  const float ay = gy * K.fy * inv_z;
  const hf_float4 a = hf_make_float4(ax, ay, -(ax * v.x + ay * v.y) * inv_z, 0.0f);
  const float weight = p.weight * hf_reg_term_weight(p.robust, r);
  hf_reg_set_row(v, a, r, weight, row);
  return 1;
}

HF_REG_OPENCL_KERNEL(photometric, hf_photometric_pixel, hf_photometric_params)

#endif
