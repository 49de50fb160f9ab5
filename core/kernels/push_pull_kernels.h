// Push-pull fill of an image given at some pixels only (Siekawa, "Image Reconstruction from Spatially Non-uniform
// Samples", section 3.1 and its Source 1, after Gortler et al.'s lumigraph), one output pixel per call. Written in
// the subset of core/kernels/cl_compat.h and included by the C++ loop (core/push_pull.cpp) and the OpenCL kernels
// (core/opencl/push_pull.cl), so both paths compute the same sums in the same order.
//
// Layout: a level is `channels` (1..4) interleaved floats per pixel, row-major, plus one mask byte per pixel
// (1 = the pixel holds a value, 0 = empty). Level l+1 is ceil(w_l / 2) x ceil(h_l / 2): a 2x2 block cut by the
// right or bottom border simply has fewer pixels, which is what the paper's padding to a power of two amounts to
// (padded pixels are empty).
//
// - push: coarse pixel (x, y) is the mean of the values of the non-empty fine pixels {2x, 2x+1} x {2y, 2y+1};
//   mask 1 when there was at least one, else mask 0 and value 0 (the paper's "set its colour to 0").
// - pull: a fine pixel that is empty takes the value and mask of coarse pixel (x / 2, y / 2); a non-empty one
//   keeps its value. Pulling the levels from the coarsest to level 0 fills every pixel whose coarsest ancestor
//   holds a value.
#ifndef HF_CORE_KERNELS_PUSH_PULL_KERNELS_H
#define HF_CORE_KERNELS_PUSH_PULL_KERNELS_H

#include "core/kernels/cl_compat.h"

// Level 0 from the caller's values and mask, pixel i: a pixel is a sample when its mask is set and every channel
// is finite; anything else becomes an empty pixel of value 0, so no NaN or inf enters the averages. Returns 1
// when a masked pixel was dropped for a non-finite channel, else 0.
HF_INLINE int hf_push_pull_prepare_pixel(HF_GLOBAL float* values, HF_GLOBAL hf_uint8* mask, int channels, int i) {
  int finite = 1;
  for (int c = 0; c < channels; ++c) finite = finite && hf_isfinite(values[i * channels + c]);
  const int dropped = mask[i] != 0 && !finite;
  const int sample = mask[i] != 0 && finite;
  if (!sample) {
    for (int c = 0; c < channels; ++c) values[i * channels + c] = 0.0f;
  }
  mask[i] = (hf_uint8)(sample ? 1 : 0);
  return dropped;
}

// Push, coarse pixel (x, y) of the ceil(fine_width / 2) x ceil(fine_height / 2) level.
HF_INLINE void hf_push_pixel(const HF_GLOBAL float* fine, const HF_GLOBAL hf_uint8* fine_mask, int fine_width,
                             int fine_height, int channels, HF_GLOBAL float* coarse, HF_GLOBAL hf_uint8* coarse_mask,
                             int x, int y) {
  const int coarse_width = (fine_width + 1) / 2;
  const int o = y * coarse_width + x;
  int n = 0;
  for (int dy = 0; dy < 2; ++dy) {
    for (int dx = 0; dx < 2; ++dx) {
      const int fx = 2 * x + dx, fy = 2 * y + dy;
      if (fx < fine_width && fy < fine_height && fine_mask[fy * fine_width + fx] != 0) ++n;
    }
  }
  for (int c = 0; c < channels; ++c) {
    float sum = 0.0f;
    for (int dy = 0; dy < 2; ++dy) {
      for (int dx = 0; dx < 2; ++dx) {
        const int fx = 2 * x + dx, fy = 2 * y + dy;
        if (fx < fine_width && fy < fine_height && fine_mask[fy * fine_width + fx] != 0) {
          sum += fine[(fy * fine_width + fx) * channels + c];
        }
      }
    }
    coarse[o * channels + c] = n > 0 ? sum / (float)n : 0.0f;
  }
  coarse_mask[o] = (hf_uint8)(n > 0 ? 1 : 0);
}

// Pull, fine pixel (x, y): an empty pixel takes coarse pixel (x / 2, y / 2) of the level above (coarse_width wide).
HF_INLINE void hf_pull_pixel(HF_GLOBAL float* fine, HF_GLOBAL hf_uint8* fine_mask, int fine_width, int channels,
                             const HF_GLOBAL float* coarse, const HF_GLOBAL hf_uint8* coarse_mask, int coarse_width,
                             int x, int y) {
  const int i = y * fine_width + x;
  if (fine_mask[i] != 0) return;
  const int o = (y / 2) * coarse_width + x / 2;
  for (int c = 0; c < channels; ++c) fine[i * channels + c] = coarse[o * channels + c];
  fine_mask[i] = coarse_mask[o];
}

#endif
