// Trilinear samples of the TSDF read through the flat voxel-block hash (fusion/kernels/block_hash.h), in the common
// subset of C++ and OpenCL C 1.2: the OpenCL kernels that read a map on the device gather a cell here, and every
// path (those kernels, the C++ rows over VolumeSampler's cached gather) interpolates it with the same function,
// so the C++ and OpenCL results are the same floats.
//
// Conventions of fusion/kernels/raycast_kernels.h: continuous voxel coordinates put voxel centres at integers;
// cell (i, j, k) holds the voxels i..i+1, j..j+1, k..k+1, corner c = x + 2 y + 4 z (VolumeSampler::cell_corners).
#ifndef HF_FUSION_KERNELS_TSDF_SAMPLE_H
#define HF_FUSION_KERNELS_TSDF_SAMPLE_H

#include "core/kernels/cl_compat.h"
#include "fusion/kernels/block_hash.h"
#include "fusion/kernels/voxel.h"

// Where a flat map lives: the table (mask + 1 entries, home shift, look-up bound) and the pool. A struct of
// pointers and 4-byte fields for one kernel's use (not a kernel argument).
typedef struct {
  const HF_GLOBAL hf_block_entry* table;
  const HF_GLOBAL hf_voxel* pool;
  hf_uint32 mask;
  int shift;
  int max_probe;
} hf_flat_map;

// The raw sdf (the int16 as float, VolumeSampler::cell_corners' values) of cell (i, j, k)'s eight corners into
// f[8]; 1 when every corner is observed (weight >= min_weight_raw, which is >= 1: a missing block's voxels are
// never observed), else 0 (f then holds what was read so far). *least_weight_raw: the smallest raw weight of the
// eight (valid when 1 is returned).
HF_INLINE int hf_tsdf_cell_weighted(const hf_flat_map* map, int i, int j, int k, int min_weight_raw, float* f,
                                    int* least_weight_raw) {
  int least = 0x7fffffff;
  // The corners span at most 2 x 2 x 2 blocks; most cells lie inside one, so remember the last block looked up.
  int last_bx = 0, last_by = 0, last_bz = 0, slot = -1, have = 0;
  for (int c = 0; c < 8; ++c) {
    const int vi = i + (c & 1), vj = j + ((c >> 1) & 1), vk = k + ((c >> 2) & 1);
    const int bx = hf_block_of_voxel(vi), by = hf_block_of_voxel(vj), bz = hf_block_of_voxel(vk);
    if (!have || bx != last_bx || by != last_by || bz != last_bz) {
      const int e = hf_block_find(map->table, map->mask, map->shift, map->max_probe, bx, by, bz);
      slot = e < 0 ? -1 : (int)map->table[e].value - 1;
      last_bx = bx, last_by = by, last_bz = bz, have = 1;
    }
    if (slot < 0) return 0;
    const hf_voxel v = map->pool[(hf_uint64)slot * HF_VOXELS_PER_BLOCK +
                                 (hf_uint64)hf_voxel_index(vi - HF_BLOCK_SIZE * bx, vj - HF_BLOCK_SIZE * by,
                                                           vk - HF_BLOCK_SIZE * bz)];
    if ((int)v.weight < min_weight_raw) return 0;
    f[c] = (float)v.sdf;
    least = (int)v.weight < least ? (int)v.weight : least;
  }
  *least_weight_raw = least;
  return 1;
}

// The same without the weight (the raycast's gathers).
HF_INLINE int hf_tsdf_cell(const hf_flat_map* map, int i, int j, int k, int min_weight_raw, float* f) {
  int least;
  return hf_tsdf_cell_weighted(map, i, j, k, min_weight_raw, f, &least);
}

// The trilinear normalised sdf of a cell's raw corners f[8] at fractional offset (a, b, c) in [0, 1)^3, and its
// analytic gradient in the same cell (normalised sdf per voxel, *g; w = 0): along x, then y, then z, the gradient
// the derivative of the same polynomial (Bylow et al. 2013 and Canelhas et al. 2013 use this gradient; it is
// exact for the interpolant, where central differences of samples would smooth over two cells).
HF_INLINE float hf_trilinear_gradient(const float* raw, float a, float b, float c, hf_float4* g) {
  float f[8];
  for (int n = 0; n < 8; ++n) f[n] = raw[n] * (1.0f / HF_SDF_SCALE);
  const float x00 = f[0] + a * (f[1] - f[0]), x10 = f[2] + a * (f[3] - f[2]);
  const float x01 = f[4] + a * (f[5] - f[4]), x11 = f[6] + a * (f[7] - f[6]);
  const float y0 = x00 + b * (x10 - x00), y1 = x01 + b * (x11 - x01);
  const float dx0 = (f[1] - f[0]) + b * ((f[3] - f[2]) - (f[1] - f[0]));
  const float dx1 = (f[5] - f[4]) + b * ((f[7] - f[6]) - (f[5] - f[4]));
  *g = hf_make_float4(dx0 + c * (dx1 - dx0), (x10 - x00) + c * ((x11 - x01) - (x10 - x00)), y1 - y0, 0.0f);
  return y0 + c * (y1 - y0);
}

#endif
