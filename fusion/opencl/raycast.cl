// The tracking raycast of fusion/raycast.h on an OpenCL device, over the device voxel-block hash of
// fusion/opencl/device_voxel_grid.h. Follows integrate.cl in the fusion program (fusion/opencl/CMakeLists.txt),
// whose HF_F_* constants layout and hf_real it uses.
//
// Four kernels, raycast.cpp's stages:
//   hf_raycast_clear_range  the range image's tiles to empty (near = +inf, far = 0)
//   hf_raycast_regions      per hash entry: its block's 4^3-block region into an occupancy set (the CPU's region
//                           table), for the march's jumps over empty regions
//   hf_raycast_range        per hash entry: the block's depth range, projected to the 8 x 8-pixel tiles it covers
//                           (range_image of raycast.cpp: the block clipped against the near plane, one pixel of
//                           slack; the same arithmetic in hf_real), merged with atomic min / max on the bits of the
//                           non-negative floats (their order is the integers')
//   hf_raycast_march        per pixel: around its depth hint first (march_from_hint), then march() of raycast.cpp
//                           over the tile's range (the nearest voxel's bound for
//                           cheap steps far in front of the surface, SDF-bounded trilinear steps near it, a missing
//                           block crossed in one step, the first + to - bracket refined by Illinois regula falsi)
//                           and the pixel write (depth, vertex; the normal by central differences of trilinear
//                           samples one voxel apart); the samples are fusion/kernels/tsdf_sample.h's cell gather and
//                           raycast_kernels.h's hf_trilinear, the CPU's own interpolation.
// The march samples where raycast()'s does (up to float rounding of the ray set-up): a missing block is crossed in
// one step, or its whole 4^3-block region when that holds no block (hf_raycast_regions builds the region set per
// raycast from the hash), surface-free blocks in one step when skip_blocks is set (the flags the device's
// integrate keeps, hf_fusion_surface_free, or load() copies), and a depth hint is searched first
// (march_from_hint). Colour is the trilinear colour of the hit's cell (VolumeSampler::sdf_color); shading is done
// on the host from the normals.

#include "fusion/opencl/integrate.cl"  // hf_real, the HF_F_* constants (once per program: the embedder's rule)
#include "fusion/kernels/raycast_kernels.h"
#include "fusion/kernels/tsdf_sample.h"

#define HF_RAYCAST_TILE 8
// VoxelBlockGrid::kRegionShift: a region is 4^3 blocks, 32^3 voxels.
#define HF_REGION_SHIFT 2

// floor(a / n) for n > 0, without a right shift of a negative value.
inline int hf_floor_div(int a, int n) { return a >= 0 ? a / n : -((n - 1 - a) / n); }

// A region's key in the occupancy set: 10 bits per axis (regions -512 .. 511, i.e. +-164 m at 1 cm voxels) plus
// one, so 0 marks an empty slot; 0 for a region outside that range, which then counts as occupied (no jump).
inline uint hf_region_key(int rx, int ry, int rz) {
  if (rx < -512 || rx > 511 || ry < -512 || ry > 511 || rz < -512 || rz > 511) return 0u;
  return (((uint)(rx + 512) << 20) | ((uint)(ry + 512) << 10) | (uint)(rz + 512)) + 1u;
}
inline uint hf_region_home(uint key, uint mask) { return (key * 2654435761u) & mask; }

// Per hash entry: its block's region into the occupancy set (VoxelBlockGrid::region_occupied, rebuilt per raycast;
// the set has at least twice as many slots as there are blocks, so a probe always ends).
__kernel void hf_raycast_regions(__global const hf_block_entry* table, uint entries, volatile __global uint* regions,
                                 uint region_mask) {
  const uint e = (uint)get_global_id(0);
  if (e >= entries) return;
  const hf_block_entry entry = table[e];
  if (entry.value == 0u) return;
  const int n = 1 << HF_REGION_SHIFT;
  const uint key = hf_region_key(hf_floor_div(entry.x, n), hf_floor_div(entry.y, n), hf_floor_div(entry.z, n));
  if (key == 0u) return;
  for (uint i = hf_region_home(key, region_mask), k = 0u; k <= region_mask; ++k, i = (i + 1u) & region_mask) {
    const uint old = atomic_cmpxchg(&regions[i], 0u, key);
    if (old == 0u || old == key) return;
  }
}

inline int hf_region_occupied(__global const uint* regions, uint region_mask, int rx, int ry, int rz) {
  const uint key = hf_region_key(rx, ry, rz);
  if (key == 0u) return 1;
  for (uint i = hf_region_home(key, region_mask), k = 0u; k <= region_mask; ++k, i = (i + 1u) & region_mask) {
    const uint v = regions[i];
    if (v == key) return 1;
    if (v == 0u) return 0;
  }
  return 1;
}

__kernel void hf_raycast_clear_range(__global uint* near_bits, __global uint* far_bits, uint n) {
  const uint i = (uint)get_global_id(0);
  if (i >= n) return;
  near_bits[i] = as_uint(INFINITY);
  far_bits[i] = 0u;
}

// One projected point's update of the block's bounding box (raycast.cpp's `add`).
inline void hf_raycast_box(__global const hf_real* f, hf_real qx, hf_real qy, hf_real qz, hf_real* box) {
  const hf_real u = f[HF_F_FX] * qx / qz + f[HF_F_CX], v = f[HF_F_FY] * qy / qz + f[HF_F_CY];
  box[0] = u < box[0] ? u : box[0];
  box[1] = u > box[1] ? u : box[1];
  box[2] = v < box[2] ? v : box[2];
  box[3] = v > box[3] ? v : box[3];
}

__kernel void hf_raycast_range(__global const hf_block_entry* table, uint entries, __global const hf_real* f,
                               int width, int height, int tiles_x, int tiles_y, volatile __global uint* near_bits,
                               volatile __global uint* far_bits) {
  const uint e = (uint)get_global_id(0);
  if (e >= entries) return;
  const hf_block_entry entry = table[e];
  if (entry.value == 0u) return;
  const hf_real B = f[HF_F_BLOCK_M], near_m = f[HF_F_MIN_DEPTH], far_m = f[HF_F_MAX_DEPTH];
  const hf_real c[3] = {(hf_real)entry.x * B, (hf_real)entry.y * B, (hf_real)entry.z * B};
  hf_real p0[3], ex[3], ey[3], ez[3];
  for (int r = 0; r < 3; ++r) {
    p0[r] = ((f[HF_F_R_CW + 3 * r] * c[0] + f[HF_F_R_CW + 3 * r + 1] * c[1]) + f[HF_F_R_CW + 3 * r + 2] * c[2]) +
            f[HF_F_T_CW + r];
    ex[r] = f[HF_F_R_CW + 3 * r] * B;
    ey[r] = f[HF_F_R_CW + 3 * r + 1] * B;
    ez[r] = f[HF_F_R_CW + 3 * r + 2] * B;
  }
  hf_real p[8][3];
  hf_real zmin = (hf_real)INFINITY, zmax = -(hf_real)INFINITY;
  for (int k = 0; k < 8; ++k) {
    const hf_real a = (hf_real)(k & 1), b = (hf_real)((k >> 1) & 1), cc = (hf_real)(k >> 2);
    for (int r = 0; r < 3; ++r) p[k][r] = ((p0[r] + a * ex[r]) + b * ey[r]) + cc * ez[r];
    zmin = p[k][2] < zmin ? p[k][2] : zmin;
    zmax = p[k][2] > zmax ? p[k][2] : zmax;
  }
  if (zmax < near_m || zmin > far_m) return;
  hf_real box[4] = {(hf_real)INFINITY, -(hf_real)INFINITY, (hf_real)INFINITY, -(hf_real)INFINITY};
  for (int k = 0; k < 8; ++k) {
    if (p[k][2] >= near_m) hf_raycast_box(f, p[k][0], p[k][1], p[k][2], box);
    for (int axis = 0; axis < 3; ++axis) {
      const int j = k | (1 << axis);
      if (j == k) continue;
      const hf_real za = p[k][2] - near_m, zb = p[j][2] - near_m;
      if ((za < (hf_real)0) != (zb < (hf_real)0)) {
        const hf_real s = za / (za - zb);
        hf_raycast_box(f, p[k][0] + s * (p[j][0] - p[k][0]), p[k][1] + s * (p[j][1] - p[k][1]), near_m, box);
      }
    }
  }
  if (box[1] < (hf_real)-1 || box[3] < (hf_real)-1 || box[0] > (hf_real)width || box[2] > (hf_real)height) return;
  const int tx0 = max(0, (int)floor(box[0] - (hf_real)1) / HF_RAYCAST_TILE);
  const int tx1 = min(tiles_x - 1, (int)min(ceil(box[1] + (hf_real)1), (hf_real)width) / HF_RAYCAST_TILE);
  const int ty0 = max(0, (int)floor(box[2] - (hf_real)1) / HF_RAYCAST_TILE);
  const int ty1 = min(tiles_y - 1, (int)min(ceil(box[3] + (hf_real)1), (hf_real)height) / HF_RAYCAST_TILE);
  const uint zn = as_uint((float)(zmin > near_m ? zmin : near_m)), zf = as_uint((float)zmax);
  for (int ty = ty0; ty <= ty1; ++ty)
    for (int tx = tx0; tx <= tx1; ++tx) {
      atomic_min(&near_bits[ty * tiles_x + tx], zn);
      atomic_max(&far_bits[ty * tiles_x + tx], zf);
    }
}

// What every ray shares (host-filled, floats): the march's parameters, the camera and the pose.
typedef struct {
  float R_wc[9];      // T_world_camera rotation, row-major
  float o_vox[3];     // the camera centre in continuous voxel coordinates
  float mu_m, step_fraction, min_step_m, voxel_m, refine_tol_m, min_depth_m, max_depth_m;
  int min_weight_raw;
  int skip_blocks;    // RaycastOptions::skip_blocks: cross surface-free blocks in one step
  uint region_mask;   // the region occupancy set's size - 1
  int colour;         // RaycastOptions::color: write the trilinear colour of each hit
  hf_intrinsics K;
} hf_raycast_params;

// VolumeSampler::sdf: the trilinear normalised SDF at p; 0 when a corner is unobserved or p is far off.
inline int hf_raycast_sample(const hf_flat_map* map, int min_weight_raw, float px, float py, float pz, float* s) {
  const float p[3] = {px, py, pz};
  int c[3];
  float fr[3];
  for (int a = 0; a < 3; ++a) {
    if (!(fabs(p[a]) < 1.0e9f)) return 0;
    const float fl = floor(p[a]);
    c[a] = (int)fl;
    fr[a] = p[a] - fl;
  }
  float raw[8];
  if (!hf_tsdf_cell(map, c[0], c[1], c[2], min_weight_raw, raw)) return 0;
  *s = hf_trilinear(raw[0], raw[1], raw[2], raw[3], raw[4], raw[5], raw[6], raw[7], fr[0], fr[1], fr[2]) *
       (1.0f / HF_SDF_SCALE);
  return 1;
}

// raycast.cpp's refine(): the crossing on the + to - bracket (ta, sa) .. (tb, sb).
inline float hf_raycast_refine(const hf_flat_map* map, const hf_raycast_params* P, const float* o, const float* d,
                               float ta, float sa, float tb, float sb) {
  float tc = hf_zero_crossing(ta, sa, tb, sb);
  int kept = 0;
  for (int it = 0; it < 6 && tb - ta > P->refine_tol_m; ++it) {
    float sc = 0.0f;
    if (!hf_raycast_sample(map, P->min_weight_raw, o[0] + tc * d[0], o[1] + tc * d[1], o[2] + tc * d[2], &sc) ||
        hf_refine_converged(sc, ta, sa, tb, sb, P->refine_tol_m))
      break;
    tc = hf_illinois_step(tc, sc, &ta, &sa, &tb, &sb, &kept);
  }
  return tc;
}

// Where the ray leaves the cube of `size` voxels (aligned to multiples of it) holding voxel (i, j, k): raycast.cpp's
// exit_of (a block: 8, a region: 32).
inline float hf_raycast_cube_exit(const float* o, const float* d, int i, int j, int k, int size) {
  const int v[3] = {i, j, k};
  float t_exit = INFINITY;
  for (int a = 0; a < 3; ++a) {
    if (d[a] == 0.0f) continue;
    const float lo = (float)(hf_floor_div(v[a], size) * size) - 0.5f;
    const float plane = d[a] > 0.0f ? lo + (float)size : lo;
    const float t = (plane - o[a]) * (1.0f / d[a]);
    t_exit = t < t_exit ? t : t_exit;
  }
  return t_exit;
}

// raycast.cpp's march(), step for step: 1 and *t_hit at a crossing.
inline int hf_raycast_ray(const hf_flat_map* map, __global const uint* surface_free, __global const uint* regions,
                          const hf_raycast_params* P, const float* o, const float* d, float t_min, float t_max,
                          float* t_hit) {
  const float far_sdf = 0.5f;
  const float far_margin_m = 0.8660254f * P->voxel_m;
  const int cheap_steps = far_sdf * P->mu_m - far_margin_m > P->min_step_m;
  const short far_raw = (short)(far_sdf * HF_SDF_SCALE);
  const float skip_eps = 1e-3f * P->voxel_m;
  float t = t_min;
  int have_prev = 0, prev_exact = 0;
  float t_prev = 0.0f, s_prev = 0.0f, fine_until = -1.0f;
  while (t < t_max) {
    const float p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
    int n[3];
    for (int a = 0; a < 3; ++a) {
      const float q = p[a] + 0.5f;
      if (!(fabs(q) < 1e8f)) return 0;
      n[a] = (int)floor(q);
    }
    const int bx = hf_block_of_voxel(n[0]), by = hf_block_of_voxel(n[1]), bz = hf_block_of_voxel(n[2]);
    const int e = hf_block_find(map->table, map->mask, map->shift, map->max_probe, bx, by, bz);
    if (e < 0) {
      // Jump to where the ray leaves this block, or its whole region when that holds no block at all.
      const int region = HF_BLOCK_SIZE << HF_REGION_SHIFT;
      const int empty = !hf_region_occupied(regions, P->region_mask, hf_floor_div(n[0], region),
                                            hf_floor_div(n[1], region), hf_floor_div(n[2], region));
      const float exit = hf_raycast_cube_exit(o, d, n[0], n[1], n[2], empty ? region : HF_BLOCK_SIZE);
      t = (exit > t ? exit : t) + skip_eps;
      have_prev = 0;
      continue;
    }
    const uint slot = map->table[e].value - 1u;
    if (P->skip_blocks && surface_free[slot] != 0u && t > fine_until) {
      // No surface inside this block: one long cheap step to where the ray leaves it; a crossing in the half
      // voxel along its faces shows as a negative sample right after and sends the ray back here.
      have_prev = 1, prev_exact = 0;
      t_prev = t, s_prev = 1.0f;
      const float exit = hf_raycast_cube_exit(o, d, n[0], n[1], n[2], HF_BLOCK_SIZE);
      t = (exit > t ? exit : t) + skip_eps;
      continue;
    }
    const hf_voxel nearest =
        map->pool[(ulong)slot * HF_VOXELS_PER_BLOCK +
                  (ulong)hf_voxel_index(n[0] - HF_BLOCK_SIZE * bx, n[1] - HF_BLOCK_SIZE * by,
                                        n[2] - HF_BLOCK_SIZE * bz)];
    if ((int)nearest.weight < P->min_weight_raw) {
      t += P->voxel_m;
      have_prev = 0;
      continue;
    }
    if (cheap_steps && t > fine_until && nearest.sdf > far_raw) {
      const float s_near = hf_voxel_sdf(nearest);
      have_prev = 1, prev_exact = 0;
      t_prev = t, s_prev = s_near;
      const float step = P->step_fraction * (s_near * P->mu_m - far_margin_m);
      t += step > P->min_step_m ? step : P->min_step_m;
      continue;
    }
    float s = 0.0f;
    if (!hf_raycast_sample(map, P->min_weight_raw, p[0], p[1], p[2], &s)) {
      t += P->voxel_m;
      have_prev = 0;
      continue;
    }
    if (s < 0.0f) {
      if (have_prev && !prev_exact) {
        fine_until = t;
        t = t_prev;
        have_prev = 0;
        continue;
      }
      if (have_prev) {
        *t_hit = hf_raycast_refine(map, P, o, d, t_prev, s_prev, t, s);
        return 1;
      }
      t += hf_raycast_step(s, P->mu_m, P->step_fraction, P->min_step_m);
      continue;
    }
    have_prev = 1, prev_exact = 1;
    t_prev = t, s_prev = s;
    t += hf_raycast_step(s, P->mu_m, P->step_fraction, P->min_step_m);
  }
  return 0;
}

// raycast.cpp's march_from_hint(): from the sample at the hinted t, forward when in front of the surface, else
// back towards the camera with SDF-bounded steps until a sample turns positive.
inline int hf_raycast_from_hint(const hf_flat_map* map, __global const uint* surface_free,
                                __global const uint* regions, const hf_raycast_params* P, const float* o,
                                const float* d, float t_hint, float t_min, float t_max, float* t_hit) {
  float sb = 0.0f;
  if (!hf_raycast_sample(map, P->min_weight_raw, o[0] + t_hint * d[0], o[1] + t_hint * d[1], o[2] + t_hint * d[2],
                         &sb))
    return 0;
  if (sb >= 0.0f) return hf_raycast_ray(map, surface_free, regions, P, o, d, t_hint, t_max, t_hit);
  for (float tb = t_hint;;) {
    const float ta = tb - hf_raycast_step(sb, P->mu_m, P->step_fraction, P->min_step_m);
    float sa = 0.0f;
    if (ta < t_min ||
        !hf_raycast_sample(map, P->min_weight_raw, o[0] + ta * d[0], o[1] + ta * d[1], o[2] + ta * d[2], &sa))
      return 0;
    if (sa >= 0.0f) {
      *t_hit = hf_raycast_refine(map, P, o, d, ta, sa, tb, sb);
      return 1;
    }
    tb = ta, sb = sa;
  }
}

// VolumeSampler::sdf_color's colour: the trilinear r, g, b of p's cell, rounded to 8 bits as raycast.cpp writes
// them; black when a corner is unobserved.
inline uchar4 hf_raycast_colour(const hf_flat_map* map, int min_weight_raw, const float* p) {
  int c[3];
  float fr[3];
  for (int a = 0; a < 3; ++a) {
    if (!(fabs(p[a]) < 1.0e9f)) return (uchar4)(0);
    const float fl = floor(p[a]);
    c[a] = (int)fl;
    fr[a] = p[a] - fl;
  }
  hf_voxel v[8];
  for (int k = 0; k < 8; ++k) {
    const int vi = c[0] + (k & 1), vj = c[1] + ((k >> 1) & 1), vk = c[2] + ((k >> 2) & 1);
    const int bx = hf_block_of_voxel(vi), by = hf_block_of_voxel(vj), bz = hf_block_of_voxel(vk);
    const int e = hf_block_find(map->table, map->mask, map->shift, map->max_probe, bx, by, bz);
    if (e < 0) return (uchar4)(0);
    v[k] = map->pool[(ulong)(map->table[e].value - 1u) * HF_VOXELS_PER_BLOCK +
                     (ulong)hf_voxel_index(vi - HF_BLOCK_SIZE * bx, vj - HF_BLOCK_SIZE * by, vk - HF_BLOCK_SIZE * bz)];
    if ((int)v[k].weight < min_weight_raw) return (uchar4)(0);
  }
  const float r = hf_trilinear((float)v[0].r, (float)v[1].r, (float)v[2].r, (float)v[3].r, (float)v[4].r,
                               (float)v[5].r, (float)v[6].r, (float)v[7].r, fr[0], fr[1], fr[2]);
  const float g = hf_trilinear((float)v[0].g, (float)v[1].g, (float)v[2].g, (float)v[3].g, (float)v[4].g,
                               (float)v[5].g, (float)v[6].g, (float)v[7].g, fr[0], fr[1], fr[2]);
  const float b = hf_trilinear((float)v[0].b, (float)v[1].b, (float)v[2].b, (float)v[3].b, (float)v[4].b,
                               (float)v[5].b, (float)v[6].b, (float)v[7].b, fr[0], fr[1], fr[2]);
  return (uchar4)((uchar)clamp(r + 0.5f, 0.0f, 255.0f), (uchar)clamp(g + 0.5f, 0.0f, 255.0f),
                  (uchar)clamp(b + 0.5f, 0.0f, 255.0f), (uchar)0);
}

// VolumeSampler::normal (h = 1): central differences of the trilinear samples one voxel apart at p's offset.
inline hf_float4 hf_raycast_normal(const hf_flat_map* map, int min_weight_raw, const float* p) {
  int c[3];
  float fr[3];
  for (int a = 0; a < 3; ++a) {
    if (!(fabs(p[a]) < 1.0e9f)) return hf_invalid4();
    const float fl = floor(p[a]);
    c[a] = (int)fl;
    fr[a] = p[a] - fl;
  }
  float s[6];  // -x, +x, -y, +y, -z, +z
  for (int q = 0; q < 6; ++q) {
    const int a = q / 2, sign = (q & 1) ? 1 : -1;
    int cc[3] = {c[0], c[1], c[2]};
    cc[a] += sign;
    float raw[8];
    if (!hf_tsdf_cell(map, cc[0], cc[1], cc[2], min_weight_raw, raw)) return hf_invalid4();
    s[q] = hf_trilinear(raw[0], raw[1], raw[2], raw[3], raw[4], raw[5], raw[6], raw[7], fr[0], fr[1], fr[2]);
  }
  return hf_normal_from_differences(s[1] - s[0], s[3] - s[2], s[5] - s[4]);
}

__kernel void hf_raycast_march(__global const hf_block_entry* table, uint mask, int shift, int max_probe,
                               __global const hf_voxel* pool, __global const uint* surface_free,
                               __global const uint* regions, __global const float* near_m,
                               __global const float* far_m, int tiles_x, __global const hf_real* f,
                               hf_raycast_params P, __global const float* hints, int has_hints,
                               __global float* depth, __global float4* vertices, __global float4* normals,
                               __global uchar* colour, volatile __global uint* hits) {
  const int x = (int)get_global_id(0), y = (int)get_global_id(1);
  if (x >= P.K.width || y >= P.K.height) return;
  const int pixel = y * P.K.width + x;
  hf_flat_map map;
  map.table = table;
  map.pool = pool;
  map.mask = mask;
  map.shift = shift;
  map.max_probe = max_probe;
  // The ray through the pixel at z = 1 (in the camera's real type, as PinholeCamera's doubles), its length, its
  // direction in voxel units in the world.
  const float dc[3] = {(float)(((hf_real)x - f[HF_F_CX]) / f[HF_F_FX]), (float)(((hf_real)y - f[HF_F_CY]) / f[HF_F_FY]),
                       1.0f};
  const float len = sqrt(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]);
  const float u[3] = {dc[0] / len, dc[1] / len, dc[2] / len};
  float d[3];
  for (int r = 0; r < 3; ++r)
    d[r] = ((P.R_wc[3 * r] * u[0] + P.R_wc[3 * r + 1] * u[1]) + P.R_wc[3 * r + 2] * u[2]) / P.voxel_m;
  float t = 0.0f;
  int hit = 0;
  const float hint = has_hints ? hints[pixel] : 0.0f;
  if (hint > 0.0f && isfinite(hint)) {
    // RayCaster::cast: the bracket around the depth the frame measured first.
    const float w = hf_raycast_hint_halfwidth(hint, P.mu_m, P.voxel_m);
    const float h0 = max(P.min_depth_m, hint - w), h1 = min(P.max_depth_m, hint + w);
    hit = h0 <= hint && hint <= h1 && hf_raycast_from_hint(&map, surface_free, regions, &P, P.o_vox, d, hint * len,
                                                                   h0 * len, h1 * len, &t);
  }
  const int tile = (y / HF_RAYCAST_TILE) * tiles_x + x / HF_RAYCAST_TILE;
  const float z0 = max(P.min_depth_m, near_m[tile] - P.voxel_m);
  const float z1 = min(P.max_depth_m, far_m[tile] + P.voxel_m);
  if (!hit) hit = z0 < z1 && hf_raycast_ray(&map, surface_free, regions, &P, P.o_vox, d, z0 * len, z1 * len, &t);
  if (hit) {
    const float z = t / len;
    depth[pixel] = z;
    vertices[pixel] = (float4)(dc[0] * z, dc[1] * z, z, 1.0f);
    const float p[3] = {P.o_vox[0] + t * d[0], P.o_vox[1] + t * d[1], P.o_vox[2] + t * d[2]};
    const hf_float4 n = hf_raycast_normal(&map, P.min_weight_raw, p);
    // Into the camera frame: R_wc^T n.
    normals[pixel] = hf_is_valid4(n) ? (float4)(P.R_wc[0] * n.x + P.R_wc[3] * n.y + P.R_wc[6] * n.z,
                                                P.R_wc[1] * n.x + P.R_wc[4] * n.y + P.R_wc[7] * n.z,
                                                P.R_wc[2] * n.x + P.R_wc[5] * n.y + P.R_wc[8] * n.z, 1.0f)
                                     : (float4)(0.0f);
    if (P.colour) {
      const uchar4 c = hf_raycast_colour(&map, P.min_weight_raw, p);
      colour[3 * pixel] = c.x, colour[3 * pixel + 1] = c.y, colour[3 * pixel + 2] = c.z;
    }
    atomic_inc(hits);
  } else {
    depth[pixel] = 0.0f;
    vertices[pixel] = (float4)(0.0f);
    normals[pixel] = (float4)(0.0f);
    if (P.colour) colour[3 * pixel] = colour[3 * pixel + 1] = colour[3 * pixel + 2] = (uchar)0;
  }
}
