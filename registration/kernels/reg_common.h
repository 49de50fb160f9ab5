// Registration kernels: the types and helpers every per-pixel residual shares (report section 3.1-3.3).
//
// Written in the common subset of C++ and OpenCL C (core/kernels/cl_compat.h). Included by the C++ reduction
// (registration/cpu_backend.cpp) and by the OpenCL kernels (registration/opencl/), so both compute the same rows.
//
// Frames and parameters (report eq. 10-13, 17, 26):
// - "ref" is the reference frame t (model maps from a raycast, or the previous frame), "cur" the current frame t+1.
// - The unknown is T_ref_cur = delta_T of eq. 10-11: it maps points of the current camera into the reference
//   camera, v = T_ref_cur * v_cur (eq. 13).
// - A Gauss-Newton step xi = (omega, v) (rotation first, eq. 17) updates T_ref_cur <- exp(xi) * T_ref_cur (eq. 26,
//   left multiplication with the exact exponential map), so every Jacobian below is the derivative at xi = 0 of
//   the residual with the moving point exp(xi) * v, d(exp(xi) v)/dxi = [ [-v]x  I ] (eq. 45).
// - Each residual is linearised as r(xi) ~ r + J xi; the driver solves (sum w J^T J) xi = -(sum w J^T r).
//
// The 29 reduced values, in this order (HF_REG_SUMS):
//   [0..20]  the upper triangle of H = sum w J^T J, row-major: (0,0) (0,1) .. (0,5) (1,1) .. (1,5) (2,2) .. (5,5)
//   [21..26] g = sum w J^T r
//   [27]     cost = sum w r^2
//   [28]     count = number of rows accumulated (residuals with a correspondence)
#ifndef HF_REGISTRATION_KERNELS_REG_COMMON_H
#define HF_REGISTRATION_KERNELS_REG_COMMON_H

#include "core/kernels/cl_compat.h"
#include "core/kernels/image_kernels.h"

#define HF_REG_SUMS 29
#define HF_REG_SUM_H 0
#define HF_REG_SUM_G 21
#define HF_REG_SUM_COST 27
#define HF_REG_SUM_COUNT 28
// At most this many rows per pixel (combined: one geometric and one photometric row).
#define HF_REG_MAX_ROWS 2

// Which residual a problem evaluates (the `method` field of hf_reg_params).
#define HF_REG_ICP 0
#define HF_REG_PHOTOMETRIC 1
#define HF_REG_COMBINED 2

// Robust kernels for IRLS (the `robust_*` fields of hf_reg_params).
#define HF_ROBUST_NONE 0
#define HF_ROBUST_HUBER 1      // w = 1 for |r| <= k, k / |r| beyond (k = scale)
#define HF_ROBUST_STUDENT_T 2  // w = (nu + 1) / (nu + (r / sigma)^2), sigma = scale, nu = t_dof (DVO, Kerl 2013)

// The accumulator type: double in C++, float in OpenCL (a work-item sums in float, the host sums groups in double).
#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
typedef float hf_reg_sum_t;
#else
typedef double hf_reg_sum_t;
#endif

// A rigid transform as 12 floats: m[0..8] the rotation row-major, m[9..11] the translation (metres).
typedef struct {
  float m[12];
} hf_transform12;

// One Jacobian row, its residual and its final weight (robust weight times the method's term weight).
typedef struct {
  float J[6];
  float r;
  float w;
} hf_reg_row;

// Parameters of one residual evaluation. Plain 4-byte fields only, so the struct has the same layout on the host
// and in OpenCL C and can be passed by value as a kernel argument.
typedef struct {
  int method;                  // HF_REG_ICP / HF_REG_PHOTOMETRIC / HF_REG_COMBINED
  float max_dist_m;            // reject a pair when |T v_cur - v_ref| exceeds this (ICP; photometric occlusion)
  float min_normal_cos;        // reject a pair when (R n_cur) . n_ref is below this (cos of the max angle)
  float icp_weight;            // term weight of geometric rows (1)
  float rgb_weight;            // term weight lambda of photometric rows (eq. 47-48; 1 for photometric alone)
  int robust_icp;              // HF_ROBUST_* for geometric rows
  float scale_icp;             // its k (Huber) or sigma (Student-t), metres
  int robust_rgb;              // HF_ROBUST_* for photometric rows
  float scale_rgb;             // its k or sigma, intensity units ([0, 1])
  float t_dof;                 // nu of the Student-t kernel (DVO: 5)
  float min_gradient_sq;       // photometric: skip pixels whose reference gradient |grad I|^2 is below this
  int occlusion_check;         // photometric: non-zero rejects pixels whose warped depth differs from the
                               // reference vertex at that pixel by more than max_dist_m
  int photometric_step;        // photometric rows only for current pixels with x and y multiples of this
                               // (<= 1: every pixel); geometric rows are evaluated at every pixel
} hf_reg_params;

HF_INLINE hf_float4 hf_reg_transform_point(hf_transform12 T, hf_float4 p) {
  return hf_make_float4(T.m[0] * p.x + T.m[1] * p.y + T.m[2] * p.z + T.m[9],
                        T.m[3] * p.x + T.m[4] * p.y + T.m[5] * p.z + T.m[10],
                        T.m[6] * p.x + T.m[7] * p.y + T.m[8] * p.z + T.m[11], 1.0f);
}

HF_INLINE hf_float4 hf_reg_rotate(hf_transform12 T, hf_float4 n) {
  return hf_make_float4(T.m[0] * n.x + T.m[1] * n.y + T.m[2] * n.z, T.m[3] * n.x + T.m[4] * n.y + T.m[5] * n.z,
                        T.m[6] * n.x + T.m[7] * n.y + T.m[8] * n.z, 0.0f);
}

// IRLS weight of residual r under a robust kernel with scale > 0. Always in (0, 1] for Huber, (0, (nu+1)/nu] for
// Student-t, 1 for HF_ROBUST_NONE; never NaN for finite r.
HF_INLINE float hf_reg_robust_weight(int robust, float r, float scale, float dof) {
  if (robust == HF_ROBUST_HUBER) {
    const float a = hf_fabs(r);
    return a <= scale ? 1.0f : scale / a;
  }
  if (robust == HF_ROBUST_STUDENT_T) {
    const float u = r / scale;
    return (dof + 1.0f) / (dof + u * u);
  }
  return 1.0f;
}

// The row of a residual whose derivative with respect to the moving point v (reference frame) is a:
// J = a^T [ [-v]x  I ] = [ (v x a)^T  a^T ] (eq. 24 with a = -n, eq. 35 with a = grad I dPi K).
HF_INLINE void hf_reg_set_row(hf_float4 v, hf_float4 a, float r, float w, hf_reg_row* row) {
  const hf_float4 va = hf_cross3(v, a);
  row->J[0] = va.x;
  row->J[1] = va.y;
  row->J[2] = va.z;
  row->J[3] = a.x;
  row->J[4] = a.y;
  row->J[5] = a.z;
  row->r = r;
  row->w = w;
}

// Adds one row to the 29 sums (order at the top of this file).
HF_INLINE void hf_reg_accumulate(const hf_reg_row* row, hf_reg_sum_t* sums) {
  const hf_reg_sum_t w = (hf_reg_sum_t)row->w;
  const hf_reg_sum_t r = (hf_reg_sum_t)row->r;
  int k = 0;
  for (int i = 0; i < 6; ++i) {
    const hf_reg_sum_t wJi = w * (hf_reg_sum_t)row->J[i];
    for (int j = i; j < 6; ++j) {
      sums[k] += wJi * (hf_reg_sum_t)row->J[j];
      ++k;
    }
    sums[HF_REG_SUM_G + i] += wJi * r;
  }
  sums[HF_REG_SUM_COST] += w * r * r;
  sums[HF_REG_SUM_COUNT] += (hf_reg_sum_t)1;
}

#endif
