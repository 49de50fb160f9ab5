// KinectFusion point-to-plane ICP, one pixel (report eq. 12-26). Common C++/OpenCL-C subset.
//
// Projective data association (eq. 16): the current vertex is moved into the reference camera with T_ref_cur,
// projected with the reference intrinsics and paired with the reference vertex/normal at the nearest pixel.
// The pair is rejected when a vertex or normal is invalid, the point is behind the camera or outside the image,
// the points are more than max_dist_m apart, or the rotated current normal and the reference normal disagree
// by more than acos(min_normal_cos). Row (eq. 24-25): J = -[ (v x n)^T n^T ], r = <v_ref - v, n_ref>.
// Reads HF_REG_IN_CUR_VERTICES, HF_REG_IN_CUR_NORMALS, HF_REG_IN_REF_VERTICES, HF_REG_IN_REF_NORMALS.
#ifndef HF_REGISTRATION_KERNELS_ICP_KERNEL_H
#define HF_REGISTRATION_KERNELS_ICP_KERNEL_H

#include "registration/kernels/reg_common.h"

typedef struct {
  float max_dist_m;      // reject a pair when |T v_cur - v_ref| exceeds this
  float min_normal_cos;  // reject a pair when (R n_cur) . n_ref is below this (cos of the max angle)
  float weight;          // term weight of the rows (1 alone)
  hf_reg_robust robust;  // scale in metres
  float depth_noise_ref_m;  // 0: off; else rows scaled by s = min(1, ref / z_cur)^2 (hf_icp_depth_scale)
} hf_icp_params;

// Rows weighed by the depth sensor's noise. A structured-light or ToF camera's axial noise grows with the square
// of the depth (Khoshelham and Elberink 2012, Nguyen et al. 2012; the synthetic sensor, datasets/sensor_noise.h,
// adds disparity steps of z^2 / 351 m: 2.8 mm at 1 m, 58 mm at 4.5 m), while near the camera other errors (the
// model's voxels, calibration, timing) that do not shrink with depth dominate. So sigma(z) = sigma_ref max(1,
// (z / ref)^2): the row of a point measured at depth z is scaled by s = min(1, ref / z)^2 (weight s^2, the robust
// kernel applied to s r, i.e. in the units of a residual at or nearer than ref). ref <= 0: s = 1.
HF_INLINE float hf_icp_depth_scale(float ref, float z) { return hf_reg_depth_noise_scale(ref, z); }

// Returns 1 and fills *row when pixel (x, y) of the current frame has a correspondence, else 0.
// The current and the reference camera share K.
HF_INLINE int hf_icp_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                           hf_icp_params p, hf_reg_row* row) {
  const int idx = y * K.width + x;
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[idx];
  const hf_float4 nc = hf_reg_map4(maps, HF_REG_IN_CUR_NORMALS)[idx];
  if (!hf_is_valid4(vc) || !hf_is_valid4(nc)) return 0;
  hf_float4 v;
  const int ridx = hf_reg_associate_nearest(vc, K, T, &v);
  if (ridx < 0) return 0;
  const hf_float4 vr = hf_reg_map4(maps, HF_REG_IN_REF_VERTICES)[ridx];
  const hf_float4 nr = hf_reg_map4(maps, HF_REG_IN_REF_NORMALS)[ridx];
  if (!hf_is_valid4(vr) || !hf_is_valid4(nr)) return 0;
  const hf_float4 d = hf_sub3(vr, v);
  if (!(hf_dot3(d, d) <= p.max_dist_m * p.max_dist_m)) return 0;
  if (!(hf_dot3(hf_reg_rotate(T, nc), nr) >= p.min_normal_cos)) return 0;
  const float r = hf_dot3(d, nr);
  const float s = hf_icp_depth_scale(p.depth_noise_ref_m, vc.z);
  const float weight = p.weight * s * s * hf_reg_term_weight(p.robust, s * r);
  hf_reg_set_row(v, hf_scale3(nr, -1.0f), r, weight, row);
  return 1;
}

HF_REG_OPENCL_KERNEL(icp, hf_icp_pixel, hf_icp_params)

#endif
