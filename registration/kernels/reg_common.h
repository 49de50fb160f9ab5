// Registration kernels: the types and helpers every per-pixel residual shares (report section 3.1-3.3).
//
// Written in the common subset of C++ and OpenCL C (core/kernels/cl_compat.h). Included by each method's kernel
// header (registration/kernels/<method>_kernel.h), which the C++ backend and the OpenCL program both compile, so
// both compute the same rows. Nothing here names a method: a method's pixel function reads the input maps it
// declared (hf_reg_maps, by HF_REG_IN_* slot) and its own parameter struct, and writes 0..HF_REG_MAX_ROWS rows.
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
// At most this many rows per pixel, for every method (combined: one geometric and one photometric row; a
// whitened 3-vector residual: three); the driver refuses a method that declares more.
#define HF_REG_MAX_ROWS 4

// Input map slots (hf_reg_maps::map). A method declares the slots it reads (DenseKernel::inputs); the driver fills
// the pyramid's maps, a method fills its own slots (HF_REG_IN_METHOD0..) with maps it derives itself (e.g. per-pixel
// covariances), and the OpenCL backend binds one buffer per slot. hf_float4 maps are read with hf_reg_map4().
#define HF_REG_IN_CUR_VERTICES 0   // hf_float4, camera frame, metres, w = 1 valid
#define HF_REG_IN_CUR_NORMALS 1    // hf_float4, unit, w = 1 valid
#define HF_REG_IN_CUR_INTENSITY 2  // float, [0, 1]
#define HF_REG_IN_REF_VERTICES 3
#define HF_REG_IN_REF_NORMALS 4
#define HF_REG_IN_REF_INTENSITY 5
#define HF_REG_IN_REF_GRAD_X 6     // float, intensity units per pixel
#define HF_REG_IN_REF_GRAD_Y 7
#define HF_REG_IN_METHOD0 8        // slots 8..11: maps a method prepares itself
#define HF_REG_MAX_INPUTS 12
#define HF_REG_IN_BIT(slot) (1u << (slot))

// Every input map of one level, by slot; all are K.width x K.height, row-major. Slots a method does not read may
// hold anything (the OpenCL side binds a dummy buffer).
typedef struct {
  const HF_GLOBAL float* map[HF_REG_MAX_INPUTS];
} hf_reg_maps;

HF_INLINE const HF_GLOBAL hf_float4* hf_reg_map4(const hf_reg_maps* maps, int slot) {
  return (const HF_GLOBAL hf_float4*)maps->map[slot];
}

// Robust kernels for IRLS (hf_reg_robust::type).
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

// The robust weight of one term: type HF_ROBUST_*, its scale (k or sigma, in the residual's units), nu of the
// Student-t kernel. Plain 4-byte fields, as every parameter struct of a method (each is passed by value as an
// OpenCL kernel argument, so host and device layouts must agree).
typedef struct {
  int type;  // HF_ROBUST_*
  float scale;
  float t_dof;
} hf_reg_robust;

HF_INLINE hf_float4 hf_reg_transform_point(hf_transform12 T, hf_float4 p) {
  return hf_make_float4(T.m[0] * p.x + T.m[1] * p.y + T.m[2] * p.z + T.m[9],
                        T.m[3] * p.x + T.m[4] * p.y + T.m[5] * p.z + T.m[10],
                        T.m[6] * p.x + T.m[7] * p.y + T.m[8] * p.z + T.m[11], 1.0f);
}

HF_INLINE hf_float4 hf_reg_rotate(hf_transform12 T, hf_float4 n) {
  return hf_make_float4(T.m[0] * n.x + T.m[1] * n.y + T.m[2] * n.z, T.m[3] * n.x + T.m[4] * n.y + T.m[5] * n.z,
                        T.m[6] * n.x + T.m[7] * n.y + T.m[8] * n.z, 0.0f);
}

// Projective data association (report eq. 16): moves the current vertex vc into the reference camera (*v =
// T vc) and returns the index of the reference pixel nearest to its projection, or -1 when the point is behind the
// camera or projects outside the image (the comparisons also reject NaN).
HF_INLINE int hf_reg_associate_nearest(hf_float4 vc, hf_intrinsics K, hf_transform12 T, hf_float4* v) {
  *v = hf_reg_transform_point(T, vc);
  if (!(v->z > 0.0f)) return -1;
  float px, py;
  hf_project(K, *v, &px, &py);
  if (!(px > -0.5f && py > -0.5f && px < (float)K.width - 0.5f && py < (float)K.height - 0.5f)) return -1;
  return (int)(py + 0.5f) * K.width + (int)(px + 0.5f);
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

HF_INLINE float hf_reg_term_weight(hf_reg_robust robust, float r) {
  return hf_reg_robust_weight(robust.type, r, robust.scale, robust.t_dof);
}

// The depth sensor's noise as a row scale: sigma(z) = sigma_ref max(1, (z / ref)^2) (structured light and ToF,
// Nguyen et al. 2012), so a row measured at depth z is scaled by s = min(1, ref / z)^2 (weight s^2, the robust
// kernel on s r). ref <= 0 or z <= 0: s = 1. icp's and sdf's depth_noise_ref_m (hf_icp_depth_scale is this).
HF_INLINE float hf_reg_depth_noise_scale(float ref, float z) {
  if (!(ref > 0.0f) || !(z > 0.0f)) return 1.0f;
  const float q = ref / z;
  return q < 1.0f ? q * q : 1.0f;
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

// A method's kernel header ends with HF_REG_OPENCL_KERNEL(name, pixel function, parameter type): in the OpenCL
// program (registration/opencl/registration.cl) it defines the reduction kernel hf_reg_reduce_<name>; in C++ it
// is empty (the C++ side's entry is the method's DenseKernel, registration/dense_method.h).
#ifndef HF_REG_OPENCL_KERNEL
#define HF_REG_OPENCL_KERNEL(name, pixel, params_type)
#endif

#endif
