// Generalized ICP (Segal, Haehnel and Thrun 2009), plane-to-plane, one pixel. Common C++/OpenCL-C subset.
//
// Each point carries a covariance C from its image-space neighbourhood (registration/gicp.h computes it per level
// into the method slots: the neighbourhood's eigenvectors with eigenvalues 1, 1 along the surface and epsilon
// along the normal, Segal's eq. 2 regularisation, dimensionless). Correspondences are projective (report eq. 16)
// as in icp: the current vertex moved by T_ref_cur is paired with the reference vertex at the nearest pixel, and
// rejected by the same distance and normal-angle gates (normals of the pyramid).
//
// Residual (Segal eq. 2): d = v_ref - T v_cur, cost d^T (C_ref + R C_cur R^T)^-1 d. With the Cholesky factor
// C_ref + R C_cur R^T = L L^T the cost is |L^-1 d|^2, so the pixel gives three whitened rows
// r = s L^-1 d, dr/dv = -s L^-1 (v = T v_cur the moving point, hf_reg_set_row), with s = sqrt(2 epsilon): two
// aligned planes then give r = n . d along their common normal, the point-to-plane distance in metres (so the
// robust scale is in metres, as icp's), and sqrt(epsilon) times the tangential offset. As in every Gauss-Newton
// GICP the matrix is held fixed within an iteration (its rotation is re-taken from T at the next one). The IRLS
// weight is the robust kernel of |r| (the Mahalanobis distance times s), the same for the three rows.
// Reads HF_REG_IN_CUR_VERTICES, HF_REG_IN_CUR_NORMALS, HF_REG_IN_REF_VERTICES, HF_REG_IN_REF_NORMALS and the
// covariance maps HF_REG_IN_GICP_CUR_COV_A/_B, HF_REG_IN_GICP_REF_COV_A/_B (hf_float4: A = (xx, xy, xz, yy),
// B = (yz, zz, 0, valid)).
#ifndef HF_REGISTRATION_KERNELS_GICP_KERNEL_H
#define HF_REGISTRATION_KERNELS_GICP_KERNEL_H

#include "registration/kernels/reg_common.h"

#define HF_REG_IN_GICP_CUR_COV_A HF_REG_IN_METHOD0
#define HF_REG_IN_GICP_CUR_COV_B (HF_REG_IN_METHOD0 + 1)
#define HF_REG_IN_GICP_REF_COV_A (HF_REG_IN_METHOD0 + 2)
#define HF_REG_IN_GICP_REF_COV_B (HF_REG_IN_METHOD0 + 3)

typedef struct {
  float max_dist_m;      // reject a pair when |T v_cur - v_ref| exceeds this
  float min_normal_cos;  // reject a pair when (R n_cur) . n_ref is below this
  float weight;          // term weight of the rows (1 alone)
  float residual_scale;  // s = sqrt(2 epsilon)
  hf_reg_robust robust;  // scale in metres, of |r|
  int step;              // rows only for current pixels with x and y multiples of this (<= 1: every pixel)
} hf_gicp_params;

// C_ref + R C_cur R^T from the packed covariances (c[0..5] = xx, xy, xz, yy, yz, zz).
HF_INLINE void hf_gicp_combined_covariance(hf_transform12 T, hf_float4 ca, hf_float4 cb, hf_float4 ra,
                                           hf_float4 rb, float* c) {
  const float C[9] = {ca.x, ca.y, ca.z, ca.y, ca.w, cb.x, ca.z, cb.x, cb.y};
  float A[9];  // R C
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) A[3 * i + j] = T.m[3 * i] * C[j] + T.m[3 * i + 1] * C[3 + j] + T.m[3 * i + 2] * C[6 + j];
  float B[9];  // R C R^T
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) B[3 * i + j] = A[3 * i] * T.m[3 * j] + A[3 * i + 1] * T.m[3 * j + 1] + A[3 * i + 2] * T.m[3 * j + 2];
  c[0] = ra.x + B[0];
  c[1] = ra.y + 0.5f * (B[1] + B[3]);
  c[2] = ra.z + 0.5f * (B[2] + B[6]);
  c[3] = ra.w + B[4];
  c[4] = rb.x + 0.5f * (B[5] + B[7]);
  c[5] = rb.y + B[8];
}

// The rows of L^-1 (lower triangular, L L^T = C) into li[0..5] = (i00, i10, i11, i20, i21, i22); 0 when C is not
// positive definite (never for two regularised covariances, whose sum has eigenvalues >= 2 epsilon; the test also
// rejects NaN).
HF_INLINE int hf_gicp_inverse_cholesky(const float* c, float* li) {
  if (!(c[0] > 0.0f)) return 0;
  const float l00 = hf_sqrt(c[0]);
  const float l10 = c[1] / l00, l20 = c[2] / l00;
  const float s11 = c[3] - l10 * l10;
  if (!(s11 > 0.0f)) return 0;
  const float l11 = hf_sqrt(s11);
  const float l21 = (c[4] - l20 * l10) / l11;
  const float s22 = c[5] - l20 * l20 - l21 * l21;
  if (!(s22 > 0.0f)) return 0;
  const float l22 = hf_sqrt(s22);
  const float i00 = 1.0f / l00, i11 = 1.0f / l11, i22 = 1.0f / l22;
  const float i10 = -l10 * i00 * i11;
  const float i21 = -l21 * i11 * i22;
  const float i20 = -(l20 * i00 + l21 * i10) * i22;
  li[0] = i00;
  li[1] = i10;
  li[2] = i11;
  li[3] = i20;
  li[4] = i21;
  li[5] = i22;
  return 1;
}

// Returns 3 and fills rows[0..2] when pixel (x, y) of the current frame has a correspondence with valid
// covariances, else 0. The current and the reference camera share K.
HF_INLINE int hf_gicp_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                            hf_gicp_params p, hf_reg_row* rows) {
  if (p.step > 1 && ((x % p.step) != 0 || (y % p.step) != 0)) return 0;
  const int idx = y * K.width + x;
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[idx];
  const hf_float4 nc = hf_reg_map4(maps, HF_REG_IN_CUR_NORMALS)[idx];
  const hf_float4 cb = hf_reg_map4(maps, HF_REG_IN_GICP_CUR_COV_B)[idx];
  if (!hf_is_valid4(vc) || !hf_is_valid4(nc) || !hf_is_valid4(cb)) return 0;
  hf_float4 v;
  const int ridx = hf_reg_associate_nearest(vc, K, T, &v);
  if (ridx < 0) return 0;
  const hf_float4 vr = hf_reg_map4(maps, HF_REG_IN_REF_VERTICES)[ridx];
  const hf_float4 nr = hf_reg_map4(maps, HF_REG_IN_REF_NORMALS)[ridx];
  const hf_float4 rb = hf_reg_map4(maps, HF_REG_IN_GICP_REF_COV_B)[ridx];
  if (!hf_is_valid4(vr) || !hf_is_valid4(nr) || !hf_is_valid4(rb)) return 0;
  const hf_float4 d = hf_sub3(vr, v);
  if (!(hf_dot3(d, d) <= p.max_dist_m * p.max_dist_m)) return 0;
  if (!(hf_dot3(hf_reg_rotate(T, nc), nr) >= p.min_normal_cos)) return 0;
  float c[6];
  hf_gicp_combined_covariance(T, hf_reg_map4(maps, HF_REG_IN_GICP_CUR_COV_A)[idx], cb,
                              hf_reg_map4(maps, HF_REG_IN_GICP_REF_COV_A)[ridx], rb, c);
  float li[6];
  if (!hf_gicp_inverse_cholesky(c, li)) return 0;
  const float s = p.residual_scale;
  const hf_float4 a0 = hf_make_float4(s * li[0], 0.0f, 0.0f, 0.0f);
  const hf_float4 a1 = hf_make_float4(s * li[1], s * li[2], 0.0f, 0.0f);
  const hf_float4 a2 = hf_make_float4(s * li[3], s * li[4], s * li[5], 0.0f);
  const float r0 = hf_dot3(a0, d), r1 = hf_dot3(a1, d), r2 = hf_dot3(a2, d);
  const float weight = p.weight * hf_reg_term_weight(p.robust, hf_sqrt(r0 * r0 + r1 * r1 + r2 * r2));
  hf_reg_set_row(v, hf_scale3(a0, -1.0f), r0, weight, &rows[0]);
  hf_reg_set_row(v, hf_scale3(a1, -1.0f), r1, weight, &rows[1]);
  hf_reg_set_row(v, hf_scale3(a2, -1.0f), r2, weight, &rows[2]);
  return 3;
}

HF_REG_OPENCL_KERNEL(gicp, hf_gicp_pixel, hf_gicp_params)

#endif
