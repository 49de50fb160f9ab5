// The voxel and its quantisation, shared by the C++ loops and the OpenCL kernels (core/kernels/cl_compat.h subset).
//
// 8 bytes per voxel with colour, as VoxelHashing and InfiniTAM:
//   sdf     int16, the truncated signed distance normalised by the truncation distance mu: sdf_m = sdf/32767 * mu,
//           in [-mu, mu]; positive in front of the surface (free space), negative behind it;
//   weight  uint16 in units of 1/HF_WEIGHT_SCALE, 0 = never observed;
//   r g b   uint8 colour, averaged with the same weights as the SDF;
//   flags   bit 0: the colour holds at least one sample (carving observations weigh the SDF but carry no
//           colour); other bits 0. Keeps the struct at 8 bytes and 2-byte aligned.
// The quantisation step of sdf is mu/32767 (for mu = 4 cm: 1.2 um), far below any sensor noise.
#ifndef HF_FUSION_KERNELS_VOXEL_H
#define HF_FUSION_KERNELS_VOXEL_H

#include "core/kernels/cl_compat.h"

#define HF_BLOCK_SIZE 8
#define HF_VOXELS_PER_BLOCK 512
#define HF_SDF_SCALE 32767.0f
#define HF_WEIGHT_SCALE 16.0f
#define HF_WEIGHT_MAX_RAW 65535
#define HF_VOXEL_FLAG_COLOUR 1

typedef struct {
  hf_int16 sdf;
  hf_uint16 weight;
  hf_uint8 r, g, b, flags;
} hf_voxel;

// Normalised SDF in [-1, 1].
HF_INLINE float hf_voxel_sdf(hf_voxel v) { return (float)v.sdf / HF_SDF_SCALE; }
HF_INLINE float hf_voxel_weight(hf_voxel v) { return (float)v.weight / HF_WEIGHT_SCALE; }

// Round to nearest, clamped to the representable range.
HF_INLINE hf_int16 hf_quantise_sdf(float sdf_normalised) {
  float s = sdf_normalised * HF_SDF_SCALE;
  s = s > HF_SDF_SCALE ? HF_SDF_SCALE : (s < -HF_SDF_SCALE ? -HF_SDF_SCALE : s);
  return (hf_int16)(s >= 0.0f ? s + 0.5f : s - 0.5f);
}
HF_INLINE hf_uint16 hf_quantise_weight(float weight) {
  float w = weight * HF_WEIGHT_SCALE + 0.5f;
  w = w > (float)HF_WEIGHT_MAX_RAW ? (float)HF_WEIGHT_MAX_RAW : (w < 0.0f ? 0.0f : w);
  return (hf_uint16)w;
}

// Index of voxel (x, y, z) in its block, 0 <= x, y, z < 8: x fastest.
HF_INLINE int hf_voxel_index(int x, int y, int z) { return x + HF_BLOCK_SIZE * (y + HF_BLOCK_SIZE * z); }

#endif
