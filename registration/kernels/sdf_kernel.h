// "sdf" (registration/sdf.h): direct volume tracking, one row per current pixel (Bylow et al. 2013; Canelhas et al.
// 2013; report section 3.5), in the common subset of C++ and OpenCL C 1.2 (core/kernels/cl_compat.h):
//
//   v = T vc                 the current vertex in the reference camera (T = T_ref_cur)
//   q = T_world_ref v        in the map; p = q / voxel_m - 1/2 in continuous voxel coordinates
//   r = D(q) = mu d(p)       d: the trilinear normalised TSDF of p's cell, mu the truncation distance (metres)
//   dr/dv = R_world_ref^T (mu / voxel_m) grad d       grad d: the analytic gradient of the same cell
//   weight: the robust kernel's, times the optional depth-noise scale and model confidence (SdfOptions)
//
// A pixel gives a row only where its vertex is valid, its cell's eight voxels are observed and |d| < max_abs_sdf
// (in the truncated band the field is flat: no gradient, and its value is a bound, not a distance).
//
// The cell is gathered two ways, the arithmetic around it is this header's in both: the C++ rows (registration/
// sdf.cpp) read the host grid through VolumeSampler::cell_corners; hf_sdf_pixel, the OpenCL kernel's pixel
// function, reads the map in the flat layout of fusion/kernels/block_hash.h from the method slots (the table in
// HF_REG_IN_METHOD0, the voxel pool in HF_REG_IN_METHOD1). Same corners, same floats, same rows.
#ifndef HF_REGISTRATION_KERNELS_SDF_KERNEL_H
#define HF_REGISTRATION_KERNELS_SDF_KERNEL_H

#include "fusion/kernels/tsdf_sample.h"
#include "registration/kernels/reg_common.h"

#define HF_SDF_IN_TABLE HF_REG_IN_METHOD0  // hf_block_entry[table_mask + 1]
#define HF_SDF_IN_POOL (HF_REG_IN_METHOD0 + 1)  // hf_voxel[blocks * HF_VOXELS_PER_BLOCK]

typedef struct {
  hf_transform12 T_world_ref;  // the reference camera in the map
  float inv_voxel_m;
  float mu_m;                  // truncation distance, metres
  float max_abs_sdf;           // rows only where |normalised sdf| < this
  int min_weight_raw;          // voxels with a raw weight below this count as unobserved (>= 1)
  int step;                    // rows only for pixels with x and y multiples of this (<= 1: every pixel)
  hf_reg_robust robust;        // of the distance in metres
  hf_uint32 table_mask;        // the flat map (hf_sdf_pixel only): entries - 1, the home shift, look-up bound
  int table_shift;
  int table_max_probe;
  float depth_noise_ref_m;     // 0: off; else rows scaled by s = min(1, ref / z)^2, z = v.z (hf_reg_depth_noise_scale)
  float confidence_weight_raw; // 0: off; else rows weighed by min(1, w / this), w the cell's least raw voxel weight
} hf_sdf_params;

// Step one: the moved vertex *v = T vc and its cell in the map (cell[3], fractional offsets frac[3]); 0 when the
// vertex is invalid, off the step grid or not finite in voxel units.
HF_INLINE int hf_sdf_locate(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                            hf_sdf_params p, hf_float4* v, int* cell, float* frac) {
  if (p.step > 1 && ((x % p.step) != 0 || (y % p.step) != 0)) return 0;
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[y * K.width + x];
  if (!hf_is_valid4(vc)) return 0;
  *v = hf_reg_transform_point(T, vc);
  const hf_float4 q = hf_reg_transform_point(p.T_world_ref, *v);
  const float pv[3] = {q.x * p.inv_voxel_m - 0.5f, q.y * p.inv_voxel_m - 0.5f, q.z * p.inv_voxel_m - 0.5f};
  for (int i = 0; i < 3; ++i) {
    if (!(hf_fabs(pv[i]) < 1e9f)) return 0;  // also NaN
    const float fl = hf_floor(pv[i]);
    cell[i] = (int)fl;
    frac[i] = pv[i] - fl;
  }
  return 1;
}

// Step two, from the cell's raw corners (hf_tsdf_cell / VolumeSampler::cell_corners) and the least raw weight of
// its eight voxels (read only when p.confidence_weight_raw > 0): the row, or 0.
HF_INLINE int hf_sdf_row(const float* raw, const float* frac, hf_float4 v, hf_sdf_params p, float cell_weight_raw,
                         hf_reg_row* row) {
  hf_float4 g;
  const float d = hf_trilinear_gradient(raw, frac[0], frac[1], frac[2], &g);
  if (!(hf_fabs(d) < p.max_abs_sdf)) return 0;
  const float r = d * p.mu_m;
  // R_world_ref^T (mu / voxel) grad d: the gradient in the reference camera's frame, metres per metre.
  const float s = p.mu_m * p.inv_voxel_m;
  const float gx = g.x * s, gy = g.y * s, gz = g.z * s;
  const float* m = p.T_world_ref.m;
  const hf_float4 a = hf_make_float4(m[0] * gx + m[3] * gy + m[6] * gz, m[1] * gx + m[4] * gy + m[7] * gz,
                                     m[2] * gx + m[5] * gy + m[8] * gz, 0.0f);
  if (!(hf_isfinite(a.x) && hf_isfinite(a.y) && hf_isfinite(a.z))) return 0;
  // The depth noise (SdfOptions::depth_noise_ref_m): z is the vertex's depth in the reference camera, which the
  // motion between two frames leaves within millimetres of its measured depth. s = 1 when off: the same bits.
  const float sc = hf_reg_depth_noise_scale(p.depth_noise_ref_m, v.z);
  // The model's confidence (SdfOptions::confidence_weight): a cell whose least-seen voxel was observed w times
  // counts w / ref of a settled one. 1 when off: the same bits.
  const float ratio = p.confidence_weight_raw > 0.0f ? cell_weight_raw / p.confidence_weight_raw : 1.0f;
  const float conf = ratio < 1.0f ? ratio : 1.0f;
  hf_reg_set_row(v, a, r, conf * sc * sc * hf_reg_term_weight(p.robust, sc * r), row);
  return 1;
}

// The pixel function over the flat map in the method slots.
HF_INLINE int hf_sdf_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                           hf_sdf_params p, hf_reg_row* rows) {
  hf_float4 v;
  int cell[3];
  float frac[3];
  if (!hf_sdf_locate(x, y, maps, K, T, p, &v, cell, frac)) return 0;
  hf_flat_map map;
  map.table = (const HF_GLOBAL hf_block_entry*)maps->map[HF_SDF_IN_TABLE];
  map.pool = (const HF_GLOBAL hf_voxel*)maps->map[HF_SDF_IN_POOL];
  map.mask = p.table_mask;
  map.shift = p.table_shift;
  map.max_probe = p.table_max_probe;
  float raw[8];
  int least = 0;
  if (!hf_tsdf_cell_weighted(&map, cell[0], cell[1], cell[2], p.min_weight_raw, raw, &least)) return 0;
  return hf_sdf_row(raw, frac, v, p, (float)least, rows);
}

HF_REG_OPENCL_KERNEL(sdf, hf_sdf_pixel, hf_sdf_params)

#endif
