// build_frame_pyramid (registration/frame_pyramid.h) on an OpenCL device: one kernel per step, each the per-pixel
// function of core/kernels/image_kernels.h that the C++ step calls (core/pyramid.cpp, core/filters.cpp,
// core/normals.cpp), so the two paths cannot drift. Embedded by registration/opencl/CMakeLists.txt and built once
// per context by registration/opencl/device_pyramid.cpp. Every kernel runs over its output image (2-D: x, y).
// No contraction into fused multiply-adds (the C++ side has none either, x86-64 SSE2).
#pragma OPENCL FP_CONTRACT OFF

#include "core/kernels/image_kernels.h"

// build_frame_pyramid's input rule: finite, > 0, >= min_m and (max_m <= 0 or <= max_m), else 0.
__kernel void hf_pyr_keep_depth(__global const float* src, int width, int height, float min_m, float max_m,
                                __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  const float z = src[y * width + x];
  const int keep = isfinite(z) && z > 0.0f && z >= min_m && (max_m <= 0.0f || z <= max_m);
  dst[y * width + x] = keep ? z : 0.0f;
}

// pyr_down_depth (core/pyramid.h): dst is (src_width / 2) x (src_height / 2).
__kernel void hf_pyr_down_depth(__global const float* src, int src_width, int src_height, float max_diff_m,
                                __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1), w = src_width / 2;
  if (x >= w || y >= src_height / 2) return;
  dst[y * w + x] = hf_pyrdown_depth_pixel(src, src_width, src_height, x, y, max_diff_m);
}

// pyr_down_gaussian (core/pyramid.h).
__kernel void hf_pyr_down_gaussian(__global const float* src, int src_width, int src_height, __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1), w = src_width / 2;
  if (x >= w || y >= src_height / 2) return;
  dst[y * w + x] = hf_pyrdown_gaussian_pixel(src, src_width, src_height, x, y);
}

// bilateral_filter_depth (core/filters.h).
__kernel void hf_pyr_bilateral(__global const float* src, int width, int height, int radius_px,
                               float inv_two_sigma_s2, float inv_two_sigma_r2, __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  dst[y * width + x] = hf_bilateral_depth_pixel(src, width, height, x, y, radius_px, inv_two_sigma_s2,
                                                inv_two_sigma_r2);
}

// build_model_pyramid's depth of a model vertex map (registration/frame_pyramid.cpp).
__kernel void hf_pyr_model_depth(__global const float4* vertices, int width, int height, __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  dst[y * width + x] = hf_model_depth_pixel(vertices[y * width + x]);
}

// compute_vertex_map and compute_normal_map (core/normals.h).
__kernel void hf_pyr_vertices(__global const float* depth, hf_intrinsics K, __global float4* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= K.width || y >= K.height) return;
  dst[y * K.width + x] = hf_vertex_pixel(depth, K, x, y);
}

__kernel void hf_pyr_normals(__global const float4* vertices, int width, int height, float max_depth_jump_ratio,
                             __global float4* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  dst[y * width + x] = hf_normal_pixel(vertices, width, height, x, y, max_depth_jump_ratio);
}

// intensity_from_color (core/image.h): BT.601 luma in [0, 1].
__kernel void hf_pyr_intensity(__global const uchar* rgb, int width, int height, __global float* dst) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  const int i = y * width + x;
  dst[i] = (0.299f * (float)rgb[3 * i] + 0.587f * (float)rgb[3 * i + 1] + 0.114f * (float)rgb[3 * i + 2]) *
           (1.0f / 255.0f);
}

// image_gradients (core/filters.h).
__kernel void hf_pyr_gradients(__global const float* img, int width, int height, __global float* gx,
                               __global float* gy) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= width || y >= height) return;
  float a, b;
  hf_gradient_pixel(img, width, height, x, y, &a, &b);
  gx[y * width + x] = a;
  gy[y * width + x] = b;
}
