// The common subset of C++ and OpenCL C that every shared kernel header is written in.
//
// A kernel header (core/kernels/*.h, later fusion/kernels, registration/kernels) includes only this file and
// uses only: plain functions marked HF_INLINE, hf_float4 values, scalar float/int, and pointers qualified with
// HF_GLOBAL. No templates, no references, no namespaces, no std::. The C++ loops and the .cl kernels include the
// same header, so the two paths cannot drift apart.
#ifndef HF_CORE_KERNELS_CL_COMPAT_H
#define HF_CORE_KERNELS_CL_COMPAT_H

#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
#define HF_GLOBAL __global
#define HF_CONSTANT __constant
#define HF_INLINE inline
typedef float4 hf_float4;
typedef short hf_int16;
typedef ushort hf_uint16;
typedef uchar hf_uint8;
HF_INLINE hf_float4 hf_make_float4(float x, float y, float z, float w) { return (float4)(x, y, z, w); }
#define hf_sqrt sqrt
#define hf_fabs fabs
#define hf_exp exp
#define hf_floor floor
#define hf_isfinite isfinite
#else
#include <cmath>
#include <cstdint>
typedef std::int16_t hf_int16;
typedef std::uint16_t hf_uint16;
typedef std::uint8_t hf_uint8;
#define HF_GLOBAL
#define HF_CONSTANT
#define HF_INLINE inline
// 16-byte aligned like OpenCL's float4, so images of hf_float4 can be copied to device buffers unchanged.
struct alignas(16) hf_float4 {
  float x, y, z, w;
};
HF_INLINE hf_float4 hf_make_float4(float x, float y, float z, float w) { return hf_float4{x, y, z, w}; }
HF_INLINE float hf_sqrt(float v) { return std::sqrt(v); }
HF_INLINE float hf_fabs(float v) { return std::fabs(v); }
HF_INLINE float hf_exp(float v) { return std::exp(v); }
HF_INLINE float hf_floor(float v) { return std::floor(v); }
HF_INLINE bool hf_isfinite(float v) { return std::isfinite(v); }
#endif

// Vertices and normals are hf_float4 with w = 1 when valid and w = 0 when invalid (no NaNs in maps, so
// reductions never see them).
HF_INLINE hf_float4 hf_invalid4(void) { return hf_make_float4(0.0f, 0.0f, 0.0f, 0.0f); }
HF_INLINE int hf_is_valid4(hf_float4 a) { return a.w != 0.0f; }
HF_INLINE hf_float4 hf_sub3(hf_float4 a, hf_float4 b) { return hf_make_float4(a.x - b.x, a.y - b.y, a.z - b.z, 0.0f); }
HF_INLINE hf_float4 hf_add3(hf_float4 a, hf_float4 b) { return hf_make_float4(a.x + b.x, a.y + b.y, a.z + b.z, 0.0f); }
HF_INLINE hf_float4 hf_scale3(hf_float4 a, float s) { return hf_make_float4(a.x * s, a.y * s, a.z * s, 0.0f); }
HF_INLINE float hf_dot3(hf_float4 a, hf_float4 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
HF_INLINE hf_float4 hf_cross3(hf_float4 a, hf_float4 b) {
  return hf_make_float4(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x, 0.0f);
}
HF_INLINE float hf_norm3(hf_float4 a) { return hf_sqrt(hf_dot3(a, a)); }

// Pinhole intrinsics as a plain struct so kernels can take them by value (equations 3-8 of the report).
typedef struct {
  float fx, fy, cx, cy;
  int width, height;
} hf_intrinsics;

// Equation 3: v(p) = ((px - cx) / fx * d, (py - cy) / fy * d, d). Pixel centres are at integer coordinates,
// as in TUM's and KinectFusion's convention.
HF_INLINE hf_float4 hf_backproject(hf_intrinsics K, float px, float py, float d) {
  return hf_make_float4((px - K.cx) / K.fx * d, (py - K.cy) / K.fy * d, d, 1.0f);
}

// Equation 4: p(v) = (fx vx / vz + cx, fy vy / vz + cy). The caller checks vz > 0.
HF_INLINE void hf_project(hf_intrinsics K, hf_float4 v, float* px, float* py) {
  *px = K.fx * v.x / v.z + K.cx;
  *py = K.fy * v.y / v.z + K.cy;
}

#endif
