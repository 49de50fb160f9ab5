// Compiled by CTest (core_image_kernels_opencl_c12) with clang -x cl -cl-std=CL1.2 -fsyntax-only: one kernel per
// function of core/kernels/image_kernels.h, so the shared header is checked as real OpenCL C, not only as C++.
#include "core/kernels/image_kernels.h"

__kernel void check_pyrdown_gaussian(__global const float* src, int sw, int sh, __global float* dst) {
  const int x = get_global_id(0), y = get_global_id(1);
  dst[y * (sw / 2) + x] = hf_pyrdown_gaussian_pixel(src, sw, sh, x, y);
}

__kernel void check_pyrdown_depth(__global const float* src, int sw, int sh, float max_diff_m, __global float* dst) {
  const int x = get_global_id(0), y = get_global_id(1);
  dst[y * (sw / 2) + x] = hf_pyrdown_depth_pixel(src, sw, sh, x, y, max_diff_m);
}

__kernel void check_bilateral(__global const float* src, int w, int h, int radius, float iss, float irr,
                              __global float* dst) {
  const int x = get_global_id(0), y = get_global_id(1);
  dst[y * w + x] = hf_bilateral_depth_pixel(src, w, h, x, y, radius, iss, irr);
}

__kernel void check_vertex_normal(__global const float* depth, hf_intrinsics K, float ratio,
                                  __global hf_float4* vmap, __global hf_float4* nmap) {
  const int x = get_global_id(0), y = get_global_id(1);
  vmap[y * K.width + x] = hf_vertex_pixel(depth, K, x, y);
  barrier(CLK_GLOBAL_MEM_FENCE);
  nmap[y * K.width + x] = hf_normal_pixel(vmap, K.width, K.height, x, y, ratio);
}

__kernel void check_gradient(__global const float* img, int w, int h, __global float* gx, __global float* gy) {
  const int x = get_global_id(0), y = get_global_id(1);
  float dx, dy;
  hf_gradient_pixel(img, w, h, x, y, &dx, &dy);
  gx[y * w + x] = dx;
  gy[y * w + x] = dy;
}

__kernel void check_bilinear(__global const float* img, int w, int h, __global const float* xy, __global float* out) {
  const int i = get_global_id(0);
  float v = 0.0f;
  const int ok = hf_sample_bilinear(img, w, h, xy[2 * i], xy[2 * i + 1], i & 1, &v);
  out[i] = ok ? v : -1.0f;
}
