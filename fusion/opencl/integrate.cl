// integrate() of fusion/integrate.h on an OpenCL device, over the device voxel-block hash of
// fusion/opencl/device_voxel_grid.h. Embedded into the binary by registration/opencl/embed_opencl.cmake (the shared
// headers inlined) and built once per context by device_voxel_grid.cpp.
//
// One frame is eight kernels, in order:
//   hf_fusion_band_ends     per pixel: the truncation band [d - mu, d + mu] of its ray in block units and its end
//                           cells, the same arithmetic and order as the CPU's phase 1 (band_row, integrate_cpu.cpp)
//   hf_fusion_bands         per pixel: the blocks its band crosses (Amanatides-Woo, traverse in integrate.cpp),
//                           appended to a key list, with the CPU's neighbour skip
//   hf_fusion_find          per listed key: the block's hash entry (lock-free look-up, no writer runs); found
//                           blocks join the frame's visible list once (a per-entry frame stamp), missing keys go to
//                           a second list
//   hf_fusion_create        one work-item: inserts the missing keys (duplicates among them found by the probe), a
//                           pool slot each from a bump counter; pool full or a probe longer than the bound sets an
//                           error flag and stops (the host throws CapacityError; nothing is updated)
//   hf_fusion_block_frames  per visible block: block_in_view and the camera-frame centre of its voxel (0, 0, 0),
//                           as integrate.cpp computes them (double where the device has fp64)
//   hf_point_to_plane       per pixel (point-to-plane only): hf_point_to_plane_factor
//   hf_fusion_update        per voxel of a visible block: hf_voxel_pixel + hf_integrate_voxel_at, the shared kernel
//                           the CPU loops call
//   hf_fusion_surface_free  per visible block: its surface-free flag (VoxelBlockGrid::surface_free), for the raycast
// Every kernel after hf_fusion_create returns at once when the error flag is set.
//
// Build options set by the host:
//   -DHF_FP64=1   the geometry of phase 1 and of the block frames in double (cl_khr_fp64), bit for bit the CPU's;
//                 otherwise in float (blocks on a band's edge may then differ from the CPU's).
// The C++ side is IEEE single and double without fused multiply-adds (x86-64 SSE2, integrate_cpu.cpp is built
// with -ffp-contract=off): forbid contraction here too; the host adds -cl-fp32-correctly-rounded-divide-sqrt.
#pragma OPENCL FP_CONTRACT OFF

#include "fusion/kernels/block_hash.h"  // hf_block_entry, hf_block_home, hf_block_find: VoxelBlockGrid's hash
#include "fusion/kernels/integrate_kernels.h"

#if HF_FP64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double hf_real;
#else
typedef float hf_real;
#endif

// Counters and flags (one uint buffer, zeroed by the host per frame except HF_C_POOL_NEXT).
#define HF_C_POOL_NEXT 0      // pool slots handed out (persistent)
#define HF_C_EMITTED 1        // keys appended by hf_fusion_bands (may exceed the list: HF_E_LIST)
#define HF_C_MISSING 2        // keys hf_fusion_find did not find
#define HF_C_VISIBLE 3        // blocks of this frame
#define HF_C_ERROR 4          // HF_E_* bits
#define HF_C_UPDATED 5        // voxels updated
#define HF_C_PIXELS 6         // depth pixels in range (IntegrateStats::pixels_used)
#define HF_C_CREATED 7        // blocks created by this frame
#define HF_C_IN_VIEW 8        // visible blocks in view
#define HF_C_ERROR_KEY 9      // with HF_E_POOL / HF_E_PROBE: x, y, z of the block that failed (3 values)
#define HF_E_POOL 1u
#define HF_E_PROBE 2u
#define HF_E_LIST 4u

// The frame's constants (hf_real buffer), written by the host in this order.
#define HF_F_R_WC 0           // T_world_camera rotation, row-major (9)
#define HF_F_T_WC 9           // and translation (3)
#define HF_F_INV_BLOCK 12
#define HF_F_MU 13
#define HF_F_MIN_DEPTH 14
#define HF_F_MAX_DEPTH 15
#define HF_F_FX 16            // the camera in double (PinholeCamera), for the rays and block_in_view
#define HF_F_FY 17
#define HF_F_CX 18
#define HF_F_CY 19
#define HF_F_R_CW 20          // T_camera_world rotation, row-major (9)
#define HF_F_T_CW 29          // and translation (3)
#define HF_F_VOXEL_M 32
#define HF_F_BLOCK_M 33
#define HF_F_COUNT 34

// Block keys in the list: (x, y, z) + 2^20 in 21 bits each, as integrate.cpp packs them.
#define HF_COORD_BIAS 1048576
inline ulong hf_pack_block(int x, int y, int z) {
  return ((ulong)(x + HF_COORD_BIAS) << 42) | ((ulong)(y + HF_COORD_BIAS) << 21) | (ulong)(z + HF_COORD_BIAS);
}
inline int4 hf_unpack_block(ulong k) {
  const ulong m = (1ul << 21) - 1ul;
  return (int4)((int)((k >> 42) & m) - HF_COORD_BIAS, (int)((k >> 21) & m) - HF_COORD_BIAS,
                (int)(k & m) - HF_COORD_BIAS, 0);
}

// band_row (fusion/integrate_cpu.cpp) for one pixel: the band's two ends in block units and whether the pixel
// counts (depth in range, ends inside the packable range). Same operations in the same order.
#define HF_BAND_LIMIT (1048576.0 - 2.0)
inline int hf_band_ends(__global const float* depth, int u, int v, int width, __global const hf_real* f,
                        hf_real* a, hf_real* b) {
  const hf_real d = (hf_real)depth[v * width + u];
  int ok = d >= f[HF_F_MIN_DEPTH] && d <= f[HF_F_MAX_DEPTH];
  const hf_real ray_x = ((hf_real)u - f[HF_F_CX]) / f[HF_F_FX];
  const hf_real ray_y = ((hf_real)v - f[HF_F_CY]) / f[HF_F_FY];
  const hf_real z0 = d - f[HF_F_MU] > (hf_real)1e-3 ? d - f[HF_F_MU] : (hf_real)1e-3;
  const hf_real z[2] = {z0, d + f[HF_F_MU]};
  for (int end = 0; end < 2; ++end) {
    const hf_real x = ray_x * z[end], y = ray_y * z[end];
    for (int i = 0; i < 3; ++i) {
      const hf_real q = (((f[HF_F_R_WC + 3 * i] * x + f[HF_F_R_WC + 3 * i + 1] * y) + f[HF_F_R_WC + 3 * i + 2] * z[end]) +
                         f[HF_F_T_WC + i]) *
                        f[HF_F_INV_BLOCK];
      if (end == 0)
        a[i] = q;
      else
        b[i] = q;
      ok = ok && q > (hf_real)-HF_BAND_LIMIT && q < (hf_real)HF_BAND_LIMIT;
    }
  }
  return ok;
}

// The pixel's six end cells (floor of the band ends); 0 when the pixel does not count.
inline int hf_band_cells(__global const float* depth, int u, int v, int width, __global const hf_real* f,
                         int* cells, hf_real* a, hf_real* b) {
  const int ok = hf_band_ends(depth, u, v, width, f, a, b);
  for (int i = 0; i < 3; ++i) {
    cells[i] = ok ? (int)floor(a[i]) : 0;
    cells[3 + i] = ok ? (int)floor(b[i]) : 0;
  }
  return ok;
}

inline void hf_emit_block(int x, int y, int z, __global ulong* list, uint list_capacity,
                          volatile __global uint* counters) {
  const uint i = atomic_inc(&counters[HF_C_EMITTED]);
  if (i < list_capacity)
    list[i] = hf_pack_block(x, y, z);
  else
    atomic_or(&counters[HF_C_ERROR], HF_E_LIST);
}

// Per pixel, its band ends (6 reals) and end cells (6 ints, x y z of the start then of the end) and whether it counts:
// written once, read by hf_fusion_bands for the pixel and as its right and lower neighbours' skip test.
__kernel void hf_fusion_band_ends(__global const float* depth, int width, int height, __global const hf_real* f,
                                  __global hf_real* ends, __global int* cells, __global uchar* ok) {
  const int u = (int)get_global_id(0), v = (int)get_global_id(1);
  if (u >= width || v >= height) return;
  const int p = v * width + u;
  int c[6];
  hf_real a[3], b[3];
  ok[p] = (uchar)hf_band_cells(depth, u, v, width, f, c, a, b);
  for (int i = 0; i < 3; ++i) {
    ends[6 * p + i] = a[i];
    ends[6 * p + 3 + i] = b[i];
  }
  for (int i = 0; i < 6; ++i) cells[6 * p + i] = c[i];
}

inline int hf_same_cells_at(__global const int* cells, int p, int q) {
  int same = 1;
  for (int i = 0; i < 6; ++i) same = same && cells[6 * p + i] == cells[6 * q + i];
  return same;
}

__kernel void hf_fusion_bands(__global const hf_real* ends, __global const int* cells, __global const uchar* ok,
                              int width, int height, __global ulong* list, uint list_capacity,
                              volatile __global uint* counters) {
  const int u = (int)get_global_id(0), v = (int)get_global_id(1);
  if (u >= width || v >= height) return;
  const int p = v * width + u;
  if (!ok[p]) return;
  atomic_inc(&counters[HF_C_PIXELS]);
  // integrate.cpp's skip: a ray whose band starts and ends in the same blocks as its left neighbour's, or its upper
  // neighbour's within the same group of 8 rows, is not walked.
  if (u > 0 && ok[p - 1] && hf_same_cells_at(cells, p - 1, p)) return;
  if (v % 8 != 0 && ok[p - width] && hf_same_cells_at(cells, p - width, p)) return;
  hf_real a[3], b[3];
  for (int i = 0; i < 3; ++i) {
    a[i] = ends[6 * p + i];
    b[i] = ends[6 * p + 3 + i];
  }
  // traverse() of integrate.cpp.
  int cell[3], end[3], step[3];
  hf_real t_max[3], t_delta[3];
  for (int i = 0; i < 3; ++i) {
    const hf_real dir = b[i] - a[i];
    cell[i] = cells[6 * p + i];
    end[i] = cells[6 * p + 3 + i];
    step[i] = dir > (hf_real)0 ? 1 : (dir < (hf_real)0 ? -1 : 0);
    if (step[i] == 0) {
      t_max[i] = t_delta[i] = (hf_real)INFINITY;
    } else {
      const hf_real boundary = step[i] > 0 ? (hf_real)cell[i] + (hf_real)1 : (hf_real)cell[i];
      t_max[i] = (boundary - a[i]) / dir;
      t_delta[i] = (hf_real)1 / fabs(dir);
    }
  }
  const int max_steps = abs(end[0] - cell[0]) + abs(end[1] - cell[1]) + abs(end[2] - cell[2]) + 1;
  for (int n = 0; n < max_steps; ++n) {
    hf_emit_block(cell[0], cell[1], cell[2], list, list_capacity, counters);
    const int axis = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if (t_max[axis] > (hf_real)1) break;
    cell[axis] += step[axis];
    t_max[axis] += t_delta[axis];
  }
}

inline void hf_mark_visible(uint e, __global uint* stamps, uint frame_stamp, __global uint* visible,
                            volatile __global uint* counters) {
  if (atomic_xchg(&stamps[e], frame_stamp) != frame_stamp) visible[atomic_inc(&counters[HF_C_VISIBLE])] = e;
}

__kernel void hf_fusion_find(__global const ulong* list, uint n, __global const hf_block_entry* table, uint mask,
                             int shift, int max_probe, __global uint* stamps, uint frame_stamp,
                             __global uint* visible, __global uint* missing, volatile __global uint* counters) {
  const uint i = (uint)get_global_id(0);
  if (i >= n) return;
  const int4 c = hf_unpack_block(list[i]);
  const int e = hf_block_find(table, mask, shift, max_probe, c.x, c.y, c.z);
  if (e >= 0)
    hf_mark_visible((uint)e, stamps, frame_stamp, visible, counters);
  else
    missing[atomic_inc(&counters[HF_C_MISSING])] = i;
}

// One work-item (the device's creation lock): no other kernel touches the table meanwhile.
__kernel void hf_fusion_create(__global const ulong* list, __global const uint* missing,
                               __global hf_block_entry* table, uint mask, int shift, int max_probe,
                               __global uint* stamps, uint frame_stamp, __global uint* visible,
                               uint capacity_blocks, volatile __global uint* counters) {
  if (get_global_id(0) != 0) return;
  const uint n = counters[HF_C_MISSING];
  for (uint k = 0; k < n; ++k) {
    const int4 c = hf_unpack_block(list[missing[k]]);
    uint e = hf_block_home(c.x, c.y, c.z, shift);
    int placed = 0;
    for (int i = 0; i < max_probe; ++i, e = (e + 1u) & mask) {
      const hf_block_entry entry = table[e];
      if (entry.value != 0u) {
        if (entry.x == c.x && entry.y == c.y && entry.z == c.z) {
          placed = 1;  // created earlier in this loop: already visible
          break;
        }
        continue;
      }
      const uint slot = counters[HF_C_POOL_NEXT];
      if (slot >= capacity_blocks) break;
      counters[HF_C_POOL_NEXT] = slot + 1u;
      hf_block_entry created;
      created.x = c.x;
      created.y = c.y;
      created.z = c.z;
      created.value = slot + 1u;
      table[e] = created;
      stamps[e] = frame_stamp;
      visible[counters[HF_C_VISIBLE]] = e;
      counters[HF_C_VISIBLE] += 1u;
      counters[HF_C_CREATED] += 1u;
      placed = 1;
      break;
    }
    if (!placed) {
      counters[HF_C_ERROR] |= counters[HF_C_POOL_NEXT] >= capacity_blocks ? HF_E_POOL : HF_E_PROBE;
      counters[HF_C_ERROR_KEY] = (uint)c.x;
      counters[HF_C_ERROR_KEY + 1] = (uint)c.y;
      counters[HF_C_ERROR_KEY + 2] = (uint)c.z;
      return;
    }
  }
}

// block_in_view and the voxel (0, 0, 0) centre of integrate.cpp's update_blocks, per visible block: out.xyz the
// centre in the camera frame (float, as BlockFrame::p0), out.w 1 when the block is in view.
__kernel void hf_fusion_block_frames(__global const uint* visible, uint n, __global const hf_block_entry* table,
                                     __global const hf_real* f, int width, int height, __global float4* out,
                                     volatile __global uint* counters) {
  const uint i = (uint)get_global_id(0);
  if (i >= n || counters[HF_C_ERROR] != 0u) return;
  const hf_block_entry entry = table[visible[i]];
  const hf_real block_m = f[HF_F_BLOCK_M];
  const hf_real origin[3] = {(hf_real)entry.x * block_m, (hf_real)entry.y * block_m, (hf_real)entry.z * block_m};
  hf_real u_min = (hf_real)1e300, u_max = (hf_real)-1e300, v_min = (hf_real)1e300, v_max = (hf_real)-1e300;
  int in_view = 1, straddles = 0;
  for (int corner = 0; corner < 8 && !straddles; ++corner) {
    const hf_real q[3] = {origin[0] + block_m * (hf_real)(corner & 1),
                          origin[1] + block_m * (hf_real)((corner >> 1) & 1),
                          origin[2] + block_m * (hf_real)((corner >> 2) & 1)};
    hf_real p[3];
    for (int r = 0; r < 3; ++r)
      p[r] = ((f[HF_F_R_CW + 3 * r] * q[0] + f[HF_F_R_CW + 3 * r + 1] * q[1]) + f[HF_F_R_CW + 3 * r + 2] * q[2]) +
             f[HF_F_T_CW + r];
    if (p[2] <= (hf_real)1e-6) {
      straddles = 1;  // straddles the camera plane: the per-voxel test decides
      break;
    }
    const hf_real px = f[HF_F_FX] * p[0] / p[2] + f[HF_F_CX];
    const hf_real py = f[HF_F_FY] * p[1] / p[2] + f[HF_F_CY];
    u_min = px < u_min ? px : u_min;
    u_max = px > u_max ? px : u_max;
    v_min = py < v_min ? py : v_min;
    v_max = py > v_max ? py : v_max;
  }
  if (!straddles)
    in_view = u_max >= (hf_real)-0.5 && v_max >= (hf_real)-0.5 && u_min < (hf_real)width - (hf_real)0.5 &&
              v_min < (hf_real)height - (hf_real)0.5;
  const hf_real half_voxel = (hf_real)0.5 * f[HF_F_VOXEL_M];
  const hf_real c[3] = {origin[0] + half_voxel, origin[1] + half_voxel, origin[2] + half_voxel};
  float p0[3];
  for (int r = 0; r < 3; ++r)
    p0[r] = (float)(((f[HF_F_R_CW + 3 * r] * c[0] + f[HF_F_R_CW + 3 * r + 1] * c[1]) + f[HF_F_R_CW + 3 * r + 2] * c[2]) +
                    f[HF_F_T_CW + r]);
  out[i] = (float4)(p0[0], p0[1], p0[2], in_view ? 1.0f : 0.0f);
  if (in_view) atomic_inc(&counters[HF_C_IN_VIEW]);
}

__kernel void hf_point_to_plane(__global const float* depth, hf_intrinsics K, float max_jump_m,
                                __global float* incidence) {
  const int u = (int)get_global_id(0), v = (int)get_global_id(1);
  if (u >= K.width || v >= K.height) return;
  incidence[v * K.width + u] = hf_point_to_plane_factor(depth, u, v, K, max_jump_m);
}

// One work-item per voxel: item i is voxel i % 512 of visible block i / 512. steps: the camera-frame images of one
// voxel step along the world x, y, z axes (BlockFrame::s_x, s_y, s_z).
__kernel void hf_fusion_update(__global const uint* visible, uint n, __global const hf_block_entry* table,
                               __global const float4* block_frames, float4 s_x, float4 s_y, float4 s_z,
                               __global const float* depth, __global const float* incidence, int has_incidence,
                               __global const uchar* rgb, int has_rgb, hf_intrinsics K, float mu, float max_weight,
                               float w, __global hf_voxel* pool, volatile __global uint* counters) {
  __local uint group_updated;
  if (get_local_id(0) == 0) group_updated = 0u;
  barrier(CLK_LOCAL_MEM_FENCE);
  const uint i = (uint)get_global_id(0);
  const uint block = i / HF_VOXELS_PER_BLOCK;
  if (block < n && counters[HF_C_ERROR] == 0u) {
    const float4 p0 = block_frames[block];
    if (p0.w != 0.0f) {
      const int vi = (int)(i % HF_VOXELS_PER_BLOCK);
      const int x = vi & 7, y = (vi >> 3) & 7, z = vi >> 6;
      // integrate_cpu.cpp's row_start, then + x s_x, per component left to right.
      const float px = ((p0.x + (float)z * s_z.x) + (float)y * s_y.x) + (float)x * s_x.x;
      const float py = ((p0.y + (float)z * s_z.y) + (float)y * s_y.y) + (float)x * s_x.y;
      const float pz = ((p0.z + (float)z * s_z.z) + (float)y * s_y.z) + (float)x * s_x.z;
      const int pixel = hf_voxel_pixel(px, py, pz, K);
      const uint slot = table[visible[block]].value - 1u;
      __global hf_voxel* voxel = pool + (ulong)slot * HF_VOXELS_PER_BLOCK + (ulong)vi;
      if (pixel >= 0 && hf_integrate_voxel_at(voxel, pz, pixel, depth, has_incidence ? incidence : 0,
                                              has_rgb ? rgb : 0, mu, max_weight, w))
        atomic_inc(&group_updated);
    }
  }
  barrier(CLK_LOCAL_MEM_FENCE);
  if (get_local_id(0) == 0 && group_updated != 0u) atomic_add(&counters[HF_C_UPDATED], group_updated);
}

// VoxelBlockGrid::surface_free per visible block after the update (block_is_surface_free: no observed voxel with
// sdf <= 0), into flags[pool slot], for the raycast's block skip. One work-item per block.
__kernel void hf_fusion_surface_free(__global const uint* visible, uint n, __global const hf_block_entry* table,
                                     __global const hf_voxel* pool, __global uint* flags,
                                     volatile __global uint* counters) {
  const uint i = (uint)get_global_id(0);
  if (i >= n || counters[HF_C_ERROR] != 0u) return;
  const uint slot = table[visible[i]].value - 1u;
  __global const hf_voxel* v = pool + (ulong)slot * HF_VOXELS_PER_BLOCK;
  uint surface = 0u;
  for (int k = 0; k < HF_VOXELS_PER_BLOCK; ++k) surface |= (uint)(v[k].weight != 0 && v[k].sdf <= 0);
  flags[slot] = surface ? 0u : 1u;
}

// The blocks of a visible list side by side, with their entries (the host copy of one frame's blocks): one
// work-item per voxel.
__kernel void hf_gather_blocks(__global const uint* visible, uint n, __global const hf_block_entry* table,
                               __global const hf_voxel* pool, __global hf_voxel* out,
                               __global hf_block_entry* out_entries) {
  const uint i = (uint)get_global_id(0);
  const uint block = i / HF_VOXELS_PER_BLOCK;
  if (block >= n) return;
  const hf_block_entry entry = table[visible[block]];
  if (i % HF_VOXELS_PER_BLOCK == 0u) out_entries[block] = entry;
  const uint slot = entry.value - 1u;
  out[i] = pool[(ulong)slot * HF_VOXELS_PER_BLOCK + (ulong)(i % HF_VOXELS_PER_BLOCK)];
}

// The bandwidth probe of bench/bench_fusion_opencl.cpp: dst = src, one float4 per item.
__kernel void hf_copy_float4(__global const float4* src, __global float4* dst) {
  dst[get_global_id(0)] = src[get_global_id(0)];
}
