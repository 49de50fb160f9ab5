// The push-pull fill's OpenCL kernels (core/opencl/push_pull_opencl.cpp), one work-item per output pixel, over
// the shared per-pixel maths of core/kernels/push_pull_kernels.h (Siekawa's Source 1 on buffers instead of
// image2d_t, so 1..4 channels and odd sizes work the same as in C++).
#include "core/kernels/push_pull_kernels.h"

__kernel void hf_push_pull_push(__global const float* fine, __global const uchar* fine_mask, int fine_width,
                                int fine_height, int channels, __global float* coarse, __global uchar* coarse_mask) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= (fine_width + 1) / 2 || y >= (fine_height + 1) / 2) return;
  hf_push_pixel(fine, fine_mask, fine_width, fine_height, channels, coarse, coarse_mask, x, y);
}

__kernel void hf_push_pull_pull(__global float* fine, __global uchar* fine_mask, int fine_width, int fine_height,
                                int channels, __global const float* coarse, __global const uchar* coarse_mask) {
  const int x = get_global_id(0), y = get_global_id(1);
  if (x >= fine_width || y >= fine_height) return;
  hf_pull_pixel(fine, fine_mask, fine_width, channels, coarse, coarse_mask, (fine_width + 1) / 2, x, y);
}
