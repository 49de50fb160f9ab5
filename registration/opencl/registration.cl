// OpenCL reduction of the registration normal equations (registration/reduction.h, order of the 29 sums in
// registration/kernels/reg_common.h): the part every method shares. Embedded into the binary by
// embed_opencl.cmake, which appends each registered method's kernel header (registration/methods.def) and inlines
// the shared headers, and built once per context by registration/opencl/opencl_backend.cpp. Each kernel header
// ends with HF_REG_OPENCL_KERNEL(name, pixel, params), which defines its reduction kernel hf_reg_reduce_<name>
// here; the backend picks the kernel by the method's name, so this file never names a method.
//
// Two stages (OpenCV KinFu's scheme): each work-item evaluates pixels with the method's shared per-pixel function
// and sums their rows; the work-group then adds its items' 29 sums with a tree in local memory and writes one row
// of 29 per group; the host adds the group rows in double.
//
// Build options set by the host:
//   -DHF_REG_REDUCE_DOUBLE=1  accumulate in double (devices with cl_khr_fp64). Each row's products are then
//                             formed exactly as the C++ backend forms them (float factors widened to double), so
//                             the two backends differ only by the order of the double additions.
//   (otherwise)               accumulate in float: hf_reg_accumulate() of the shared header, as on devices
//                             without fp64.
// The work-group size must be a power of two (the host takes it from the device queries).

// The C++ backend evaluates the per-pixel maths in IEEE single precision without fused multiply-adds (x86-64
// SSE); forbid contraction here too, so both paths make the same accept/reject decisions on every pixel.
#pragma OPENCL FP_CONTRACT OFF

#include "registration/kernels/reg_common.h"

#if HF_REG_MAX_INPUTS != 12
#error "HF_REG_OPENCL_KERNEL binds 12 input slots: update it with HF_REG_MAX_INPUTS"
#endif

#if HF_REG_REDUCE_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double hf_cl_acc;
#else
typedef float hf_cl_acc;
#endif

// hf_reg_accumulate() of reg_common.h with the accumulator type chosen above. With doubles it is that function's
// C++ instantiation operation for operation (w * J_i, then times J_j; w * J_i * r; w * r * r).
HF_INLINE void hf_cl_accumulate(const hf_reg_row* row, hf_cl_acc* sums) {
  const hf_cl_acc w = (hf_cl_acc)row->w;
  const hf_cl_acc r = (hf_cl_acc)row->r;
  int k = 0;
  for (int i = 0; i < 6; ++i) {
    const hf_cl_acc wJi = w * (hf_cl_acc)row->J[i];
    for (int j = i; j < 6; ++j) {
      sums[k] += wJi * (hf_cl_acc)row->J[j];
      ++k;
    }
    sums[HF_REG_SUM_G + i] += wJi * r;
  }
  sums[HF_REG_SUM_COST] += w * r * r;
  sums[HF_REG_SUM_COUNT] += (hf_cl_acc)1;
}

// Stage one's second half: adds `sums` over the work-group (tree in `scratch`, HF_REG_SUMS * local size
// accumulators, value k of item i at k * local_size + i) and writes the group's row to group_sums.
HF_INLINE void hf_cl_group_reduce(const hf_cl_acc* sums, __local hf_cl_acc* scratch,
                                  __global hf_cl_acc* group_sums) {
  const int lid = (int)get_local_id(0);
  const int ls = (int)get_local_size(0);
  for (int k = 0; k < HF_REG_SUMS; ++k) scratch[k * ls + lid] = sums[k];
  barrier(CLK_LOCAL_MEM_FENCE);
  for (int s = ls / 2; s > 0; s >>= 1) {
    if (lid < s) {
      for (int k = 0; k < HF_REG_SUMS; ++k) scratch[k * ls + lid] += scratch[k * ls + lid + s];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
  }
  if (lid == 0) {
    const int g = (int)get_group_id(0);
    for (int k = 0; k < HF_REG_SUMS; ++k) group_sums[g * HF_REG_SUMS + k] = scratch[k * ls];
  }
}

// The normal equations of one level for the method whose pixel function is PIXEL (parameter struct PARAMS): the
// kernel hf_reg_reduce_NAME. Work-item i evaluates pixels i, i + G, i + 2G, ... (G = global size) of the
// K.width x K.height maps, one buffer per input slot (HF_REG_MAX_INPUTS = 12; slots the method does not read are
// a dummy buffer).
#undef HF_REG_OPENCL_KERNEL
#define HF_REG_OPENCL_KERNEL(NAME, PIXEL, PARAMS)                                                                  \
  __kernel void hf_reg_reduce_##NAME(                                                                              \
      __global const float* m0, __global const float* m1, __global const float* m2, __global const float* m3,      \
      __global const float* m4, __global const float* m5, __global const float* m6, __global const float* m7,      \
      __global const float* m8, __global const float* m9, __global const float* m10, __global const float* m11,    \
      hf_intrinsics K, hf_transform12 T, PARAMS p, __global hf_cl_acc* group_sums, __local hf_cl_acc* scratch) {   \
    const hf_reg_maps maps = {{m0, m1, m2, m3, m4, m5, m6, m7, m8, m9, m10, m11}};                                \
    hf_cl_acc sums[HF_REG_SUMS];                                                                                   \
    for (int k = 0; k < HF_REG_SUMS; ++k) sums[k] = (hf_cl_acc)0;                                                  \
    const int n = K.width * K.height;                                                                              \
    const int stride = (int)get_global_size(0);                                                                    \
    for (int idx = (int)get_global_id(0); idx < n; idx += stride) {                                                \
      const int y = idx / K.width;                                                                                 \
      const int x = idx - y * K.width;                                                                             \
      hf_reg_row rows[HF_REG_MAX_ROWS];                                                                            \
      const int m = PIXEL(x, y, &maps, K, T, p, rows);                                                             \
      for (int k = 0; k < m; ++k) hf_cl_accumulate(&rows[k], sums);                                                \
    }                                                                                                              \
    hf_cl_group_reduce(sums, scratch, group_sums);                                                                 \
  }

// The same two-stage reduction over given rows (n rows of 8 floats: J[6], r, w, the layout of hf_reg_row), so a
// test can check the reduction alone against a double sum on the host.
__kernel void hf_reg_reduce_rows(__global const float* rows, int n, __global hf_cl_acc* group_sums,
                                 __local hf_cl_acc* scratch) {
  hf_cl_acc sums[HF_REG_SUMS];
  for (int k = 0; k < HF_REG_SUMS; ++k) sums[k] = (hf_cl_acc)0;
  const int stride = (int)get_global_size(0);
  for (int i = (int)get_global_id(0); i < n; i += stride) {
    hf_reg_row row;
    for (int j = 0; j < 6; ++j) row.J[j] = rows[i * 8 + j];
    row.r = rows[i * 8 + 6];
    row.w = rows[i * 8 + 7];
    hf_cl_accumulate(&row, sums);
  }
  hf_cl_group_reduce(sums, scratch, group_sums);
}
