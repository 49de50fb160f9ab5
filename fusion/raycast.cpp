#include "fusion/raycast.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>
#include <tuple>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/error.h"
#include "fusion/kernels/raycast_kernels.h"

namespace hf::fusion {

// ---------------------------------------------------------------------------------------------------------------
// BlockLookup

BlockLookup::BlockLookup(const VoxelBlockGrid& grid) : BlockLookup(grid.blocks()) {}

BlockLookup::BlockLookup(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks) {
  size_ = blocks.size();
  // Load factor <= 0.5 keeps linear probes short.
  const size_t n = std::bit_ceil(std::max<size_t>(16, 2 * blocks.size()));
  slots_.assign(n, Slot{});
  mask_ = n - 1;
  shift_ = 64 - std::countr_zero(n);
  for (const auto& [c, block] : blocks) {
    if (block == nullptr) throw Error("BlockLookup: null block pointer");
    size_t i = slot_of(c.x, c.y, c.z);
    while (slots_[i].block != nullptr && !(slots_[i].x == c.x && slots_[i].y == c.y && slots_[i].z == c.z))
      i = (i + 1) & mask_;
    if (slots_[i].block != nullptr) {
      --size_;  // the same coordinate twice: the first one wins
      continue;
    }
    slots_[i] = Slot{c.x, c.y, c.z, block};
  }
  // Regions: at most as many as blocks, usually far fewer; a table 2^extra times smaller than slots_ takes the
  // same hash's top bits.
  std::vector<Slot> occupied;
  for (const Slot& s : slots_)
    if (s.block != nullptr) occupied.push_back(Slot{s.x >> kRegionShift, s.y >> kRegionShift, s.z >> kRegionShift, s.block});
  std::sort(occupied.begin(), occupied.end(), [](const Slot& a, const Slot& b) {
    return std::tie(a.z, a.y, a.x) < std::tie(b.z, b.y, b.x);
  });
  occupied.erase(std::unique(occupied.begin(), occupied.end(),
                             [](const Slot& a, const Slot& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }),
                 occupied.end());
  const size_t nr = std::bit_ceil(std::max<size_t>(16, 2 * occupied.size()));
  region_extra_shift_ = std::countr_zero(n) - std::countr_zero(nr);
  regions_.assign(nr, Slot{});
  region_mask_ = nr - 1;
  for (const Slot& r : occupied) {
    size_t i = slot_of(r.x, r.y, r.z) >> region_extra_shift_;
    while (regions_[i].block != nullptr) i = (i + 1) & region_mask_;
    regions_[i] = r;
  }
}

// ---------------------------------------------------------------------------------------------------------------
// VolumeSampler

VolumeSampler::VolumeSampler(const BlockLookup& lookup, float min_weight)
    : lookup_(&lookup),
      min_weight_raw_(std::max<std::uint16_t>(1, hf_quantise_weight(std::max(0.0f, min_weight)))) {}

bool VolumeSampler::corners(const Eigen::Vector3f& p_vox, const Voxel* v[8], float f[3]) {
  const float bx = std::floor(p_vox.x()), by = std::floor(p_vox.y()), bz = std::floor(p_vox.z());
  // Far outside the int range nothing is allocated; refuse before the conversion would overflow.
  constexpr float kLimit = 1.0e9f;
  if (!(std::fabs(bx) < kLimit && std::fabs(by) < kLimit && std::fabs(bz) < kLimit)) return false;
  const int i = int(bx), j = int(by), k = int(bz);
  f[0] = p_vox.x() - bx, f[1] = p_vox.y() - by, f[2] = p_vox.z() - bz;
  if ((i & 7) != 7 && (j & 7) != 7 && (k & 7) != 7) {
    // All eight in one block: one lookup.
    const Voxel* base = voxel(i, j, k);
    if (base == nullptr) return false;
    v[0] = base, v[1] = base + 1, v[2] = base + 8, v[3] = base + 9;
    v[4] = base + 64, v[5] = base + 65, v[6] = base + 72, v[7] = base + 73;
  } else {
    for (int c = 0; c < 8; ++c) v[c] = voxel(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
  }
  for (int c = 0; c < 8; ++c)
    if (!observed(v[c])) return false;
  return true;
}

namespace {

// Trilinear interpolation is linear in the corner values: interpolating the raw int16 values and scaling once
// equals hf_voxel_sdf per corner up to float rounding, without eight divisions.
constexpr float kInvSdfScale = 1.0f / HF_SDF_SCALE;
float raw_trilinear(const Voxel* const v[8], const float f[3]) {
  return hf_trilinear(float(v[0]->sdf), float(v[1]->sdf), float(v[2]->sdf), float(v[3]->sdf), float(v[4]->sdf),
                      float(v[5]->sdf), float(v[6]->sdf), float(v[7]->sdf), f[0], f[1], f[2]);
}

}  // namespace

bool VolumeSampler::sdf(const Eigen::Vector3f& p_vox, float* out) {
  const Voxel* v[8];
  float f[3];
  if (!corners(p_vox, v, f)) return false;
  *out = raw_trilinear(v, f) * kInvSdfScale;
  return true;
}

bool VolumeSampler::sdf_color(const Eigen::Vector3f& p_vox, float* out, Eigen::Vector3f* rgb) {
  const Voxel* v[8];
  float f[3];
  if (!corners(p_vox, v, f)) return false;
  *out = raw_trilinear(v, f) * kInvSdfScale;
  auto channel = [&](auto get) {
    return hf_trilinear(float(get(v[0])), float(get(v[1])), float(get(v[2])), float(get(v[3])), float(get(v[4])),
                        float(get(v[5])), float(get(v[6])), float(get(v[7])), f[0], f[1], f[2]);
  };
  *rgb = Eigen::Vector3f(channel([](const Voxel* x) { return x->r; }), channel([](const Voxel* x) { return x->g; }),
                         channel([](const Voxel* x) { return x->b; }));
  return true;
}

template <int N>
bool VolumeSampler::row(int i, int j, int k, float* out) {
  bool ok = true;
  if ((i & 7) + N <= 8) {
    const Voxel* v = voxel(i, j, k);
    if (v == nullptr) return false;
    for (int c = 0; c < N; ++c) {
      ok &= v[c].weight >= min_weight_raw_;  // no early exit: all N loads are issued together
      out[c] = float(v[c].sdf);
    }
    return ok;
  }
  for (int c = 0; c < N; ++c) {
    const Voxel* v = voxel(i + c, j, k);
    if (!observed(v)) return false;
    out[c] = float(v->sdf);
  }
  return true;
}

bool VolumeSampler::normal_one_voxel(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n) {
  const float bx = std::floor(p_vox.x()), by = std::floor(p_vox.y()), bz = std::floor(p_vox.z());
  constexpr float kLimit = 1.0e9f;
  if (!(std::fabs(bx) < kLimit && std::fabs(by) < kLimit && std::fabs(bz) < kLimit)) return false;
  const int i = int(bx), j = int(by), k = int(bz);
  const float fx = p_vox.x() - bx, fy = p_vox.y() - by, fz = p_vox.z() - bz;
  // s[1 + dz][1 + dy][1 + dx] = voxel (i + dx, j + dy, k + dz), dx, dy, dz in -1 .. 2. The samples at p -+ e_x
  // need the central 2 x 2 rows (dy, dz in 0 .. 1) over dx = -1 .. 2; those at p -+ e_y and p -+ e_z need the
  // rows around them over dx = 0 .. 1. The four corner rows (dy and dz both outside 0 .. 1) are not needed.
  float s[4][4][4] = {};
  bool ok = true;
  for (int dz = 0; dz <= 1; ++dz)
    for (int dy = 0; dy <= 1; ++dy) ok = ok && row<4>(i - 1, j + dy, k + dz, &s[1 + dz][1 + dy][0]);
  for (int e = 0; e <= 1; ++e) {
    const int d = e == 0 ? -1 : 2;  // the rows one voxel outside the central 2 x 2 in y, then in z
    for (int c = 0; c <= 1; ++c) {
      ok = ok && row<2>(i, j + d, k + c, &s[1 + c][1 + d][1]);
      ok = ok && row<2>(i, j + c, k + d, &s[1 + d][1 + c][1]);
    }
  }
  if (!ok) return false;
  // Raw int16 values: the gradient's scale drops out of the normal.
  // The trilinear sample whose corner (0, 0, 0) is voxel (i + ox, j + oy, k + oz), at the shared offset f.
  auto sample = [&](int ox, int oy, int oz) {
    const int x = 1 + ox, y = 1 + oy, z = 1 + oz;
    return hf_trilinear(s[z][y][x], s[z][y][x + 1], s[z][y + 1][x], s[z][y + 1][x + 1], s[z + 1][y][x],
                        s[z + 1][y][x + 1], s[z + 1][y + 1][x], s[z + 1][y + 1][x + 1], fx, fy, fz);
  };
  const hf_float4 nn = hf_normal_from_differences(sample(1, 0, 0) - sample(-1, 0, 0),
                                                  sample(0, 1, 0) - sample(0, -1, 0),
                                                  sample(0, 0, 1) - sample(0, 0, -1));
  if (!hf_is_valid4(nn)) return false;
  *n = Eigen::Vector3f(nn.x, nn.y, nn.z);
  return true;
}

bool VolumeSampler::normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox) {
  if (h_vox == 1.0f) return normal_one_voxel(p_vox, n);
  float d[3];
  for (int a = 0; a < 3; ++a) {
    Eigen::Vector3f lo = p_vox, hi = p_vox;
    lo[a] -= h_vox;
    hi[a] += h_vox;
    float s_lo = 0.0f, s_hi = 0.0f;
    if (!sdf(lo, &s_lo) || !sdf(hi, &s_hi)) return false;
    d[a] = s_hi - s_lo;
  }
  const hf_float4 nn = hf_normal_from_differences(d[0], d[1], d[2]);
  if (!hf_is_valid4(nn)) return false;
  *n = Eigen::Vector3f(nn.x, nn.y, nn.z);
  return true;
}

// ---------------------------------------------------------------------------------------------------------------
// raycast

void RaycastOptions::validate() const {
  auto fail = [](const std::string& what) { throw Error("invalid raycast options: " + what); };
  if (!(std::isfinite(min_depth_m) && std::isfinite(max_depth_m) && min_depth_m > 0.0 && max_depth_m > min_depth_m))
    fail("expected 0 < min_depth_m < max_depth_m, got " + std::to_string(min_depth_m) + " and " +
         std::to_string(max_depth_m));
  if (!(step_fraction > 0.0 && step_fraction < 1.0))
    fail("step_fraction must be in (0, 1), got " + std::to_string(step_fraction));
  if (!(min_step_vox > 0.0 && min_step_vox <= 4.0))
    fail("min_step_vox must be in (0, 4], got " + std::to_string(min_step_vox));
  if (!(min_weight >= 0.0f)) fail("min_weight must be >= 0, got " + std::to_string(min_weight));
  if (!(refine_tol_vox > 0.0 && refine_tol_vox <= 1.0))
    fail("refine_tol_vox must be in (0, 1], got " + std::to_string(refine_tol_vox));
}

void RaycastOptions::validate(const PinholeCamera& camera) const {
  validate();
  if (depth_hint != nullptr && (depth_hint->width() != camera.width || depth_hint->height() != camera.height))
    throw Error("invalid raycast options: expected a depth_hint of the camera's size " + std::to_string(camera.width) +
                "x" + std::to_string(camera.height) + ", got " + std::to_string(depth_hint->width()) + "x" +
                std::to_string(depth_hint->height()));
}

RaycastResult raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                      const RaycastOptions& options) {
  RaycastResult out;
  raycast(grid, camera, T_world_camera, options, &out);
  return out;
}

namespace {

template <class T>
void ensure_size(Image<T>* img, int w, int h) {
  if (img->width() != w || img->height() != h) *img = Image<T>(w, h);
}

struct Hit {
  float t = 0.0f;  // metres along the unit ray
  Eigen::Vector3f p_vox;
};

// Marches one ray; see raycast.h for the scheme. o and d are in continuous voxel coordinates (d has length 1 voxel
// per voxel_m metres, i.e. d = unit direction / voxel_m) so block and voxel indices come without divisions.
//
// Each step first reads the voxel nearest to the ray point (one load from the cached block): an unobserved one is
// a corner of the trilinear sample, which is then invalid without computing it; an observed one far in front of
// the surface (sdf > kFarSdf) bounds the distance to the surface by sdf * mu - sqrt(3)/2 voxel (the SDF is a
// distance, the nearest voxel centre is at most sqrt(3)/2 voxel away), so the ray advances by step_fraction of that
// bound without interpolating. Only near the surface are trilinear samples taken; when a negative sample follows
// such a cheap step, the ray goes back to where that step started and walks the stretch again with trilinear
// samples only, so the bracket it refines is the one the all-trilinear march would have found.
bool march(VolumeSampler& sampler, const Eigen::Vector3f& o_vox, const Eigen::Vector3f& d_vox, float t_min,
           float t_max, float mu_m, float step_fraction, float min_step_m, float voxel_m, float refine_tol_m,
           Hit* hit) {
  constexpr float kFarSdf = 0.5f;
  constexpr int kRefineSteps = 6;
  const float far_margin_m = 0.8660254f * voxel_m;
  const bool cheap_steps = kFarSdf * mu_m - far_margin_m > min_step_m;
  // Block b holds continuous voxel coordinates [8 b - 0.5, 8 b + 7.5).
  const Eigen::Vector3f inv_d(d_vox.x() != 0.0f ? 1.0f / d_vox.x() : std::numeric_limits<float>::infinity(),
                              d_vox.y() != 0.0f ? 1.0f / d_vox.y() : std::numeric_limits<float>::infinity(),
                              d_vox.z() != 0.0f ? 1.0f / d_vox.z() : std::numeric_limits<float>::infinity());
  const float skip_eps = 1e-3f * voxel_m;
  float t = t_min;
  bool have_prev = false;    // a sample with sdf > 0 precedes t
  bool prev_exact = false;   // ... and it was trilinear (else the nearest voxel's value)
  float t_prev = 0.0f, s_prev = 0.0f;
  float fine_until = -1.0f;  // no cheap steps before this t (set when a bracket is walked again)
  while (t < t_max) {
    const Eigen::Vector3f p = o_vox + t * d_vox;
    const float fi = std::floor(p.x() + 0.5f), fj = std::floor(p.y() + 0.5f), fk = std::floor(p.z() + 0.5f);
    if (!(std::fabs(fi) < 1e8f && std::fabs(fj) < 1e8f && std::fabs(fk) < 1e8f)) return false;
    const int i = int(fi), j = int(fj), k = int(fk);
    const VoxelBlock* block = sampler.block(i >> 3, j >> 3, k >> 3);
    if (block == nullptr) {
      // Jump to where the ray leaves this block, or its whole region when that holds no block at all.
      constexpr int kRegionShift = BlockLookup::kRegionShift + 3;  // region size in voxels, log2
      const bool region_empty = !sampler.region_occupied(i >> kRegionShift, j >> kRegionShift, k >> kRegionShift);
      const int shift = region_empty ? kRegionShift : 3;
      const float size = float(1 << shift);
      float t_exit = std::numeric_limits<float>::infinity();
      const float lo[3] = {float(i >> shift) * size - 0.5f, float(j >> shift) * size - 0.5f,
                           float(k >> shift) * size - 0.5f};
      for (int a = 0; a < 3; ++a) {
        if (d_vox[a] == 0.0f) continue;
        const float plane = d_vox[a] > 0.0f ? lo[a] + size : lo[a];
        t_exit = std::min(t_exit, (plane - o_vox[a]) * inv_d[a]);
      }
      t = std::max(t_exit, t) + skip_eps;
      have_prev = false;
      continue;
    }
    const Voxel& nearest = block->voxels[hf_voxel_index(i & 7, j & 7, k & 7)];
    if (!sampler.observed(&nearest)) {
      t += voxel_m;  // a corner of the trilinear sample is unobserved: invalid sample
      have_prev = false;
      continue;
    }
    if (cheap_steps && t > fine_until && nearest.sdf > hf_int16(kFarSdf * HF_SDF_SCALE)) {
      const float s_near = hf_voxel_sdf(nearest);
      have_prev = true, prev_exact = false;
      t_prev = t, s_prev = s_near;
      t += std::max(step_fraction * (s_near * mu_m - far_margin_m), min_step_m);
      continue;
    }
    float s = 0.0f;
    if (!sampler.sdf(p, &s)) {
      t += voxel_m;
      have_prev = false;
      continue;
    }
    if (s < 0.0f) {
      if (have_prev && !prev_exact) {
        // The + end came from a cheap step: go back there and walk the bracket with trilinear samples only.
        fine_until = t;
        t = t_prev;
        have_prev = false;
        continue;
      }
      if (have_prev) {
        // + to - : refine on the bracket [t_prev, t] (linear interpolation, then Illinois regula falsi until the
        // bracket is below kRefineTol voxel). Converging, rather than stopping after a fixed number of steps,
        // makes the result independent of where the march happened to sample the bracket (the hinted and the
        // full march agree), and costs only samples of voxels already in cache.
        float ta = t_prev, sa = s_prev, tb = t, sb = s;
        float tc = hf_zero_crossing(ta, sa, tb, sb);
        int kept = 0;  // +1: the + end was kept last time, -1: the - end
        for (int it = 0; it < kRefineSteps && tb - ta > refine_tol_m; ++it) {
          float sc = 0.0f;
          if (!sampler.sdf(o_vox + tc * d_vox, &sc)) break;
          if (sc > 0.0f) {
            ta = tc, sa = sc;
            if (kept == -1) sb *= 0.5f;  // Illinois: the - end stays again, halve its weight
            kept = -1;
          } else if (sc < 0.0f) {
            tb = tc, sb = sc;
            if (kept == 1) sa *= 0.5f;
            kept = 1;
          } else {
            break;
          }
          tc = hf_zero_crossing(ta, sa, tb, sb);
        }
        hit->t = tc;
        hit->p_vox = o_vox + tc * d_vox;
        return true;
      }
      // Inside or behind a back face: keep going until the SDF turns positive again.
      t += hf_raycast_step(s, mu_m, step_fraction, min_step_m);
      continue;
    }
    have_prev = true, prev_exact = true;
    t_prev = t, s_prev = s;
    t += hf_raycast_step(s, mu_m, step_fraction, min_step_m);
  }
  return false;
}

}  // namespace

void raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
             const RaycastOptions& options, RaycastResult* out) {
  options.validate(camera);
  if (camera.width <= 0 || camera.height <= 0 || !(camera.fx > 0.0 && camera.fy > 0.0))
    throw Error("raycast: expected a camera with positive size and focal lengths, got " + camera.describe());
  if (!T_world_camera.is_finite()) throw Error("raycast: expected a finite T_world_camera");
  const int W = camera.width, H = camera.height;
  ensure_size(&out->depth, W, H);
  ensure_size(&out->vertices, W, H);
  ensure_size(&out->normals, W, H);
  ensure_size(&out->color, W, H);
  if (options.shade)
    ensure_size(&out->shaded, W, H);
  else
    out->shaded = ColorImage();

  const BlockLookup lookup(grid);
  const double voxel_m = grid.params().voxel_m;
  const float mu_m = float(grid.params().truncation_m());
  const Eigen::Matrix3f R = T_world_camera.rotation().cast<float>();
  const Eigen::Matrix3f R_cw = R.transpose();
  const Eigen::Vector3f o_vox = (T_world_camera.translation() / voxel_m).cast<float>() - Eigen::Vector3f::Constant(0.5f);
  const float step_fraction = float(options.step_fraction);
  const float min_step_m = float(options.min_step_vox * voxel_m);
  const float refine_tol_m = float(options.refine_tol_vox * voxel_m);
  const DepthImage* hint_image = options.depth_hint;

  // Depth range per 8 x 8 pixel tile (InfiniTAM's range image): a ray can only hit inside an allocated block, so
  // it starts at the nearest block its tile sees and stops after the farthest; tiles no block covers are not
  // marched at all. Each block is clipped against the near plane before it is projected: a block straddling the
  // near plane projects to a bounded region (its part in front of the plane), so it cannot widen every tile.
  constexpr int kTile = 8;
  const int TW = (W + kTile - 1) / kTile, TH = (H + kTile - 1) / kTile;
  std::vector<float> tile_near(size_t(TW) * TH, std::numeric_limits<float>::infinity());
  std::vector<float> tile_far(size_t(TW) * TH, 0.0f);
  {
    const SE3 T_camera_world = T_world_camera.inverse();
    const Eigen::Matrix3d Rcw = T_camera_world.rotation();
    const Eigen::Vector3d tcw = T_camera_world.translation();
    const double B = grid.params().block_m(), near_m = options.min_depth_m, far_m = options.max_depth_m;
    const Eigen::Vector3d ex = Rcw.col(0) * B, ey = Rcw.col(1) * B, ez = Rcw.col(2) * B;
    for (const auto& [c, block] : grid.blocks()) {
      (void)block;
      Eigen::Vector3d p[8];
      const Eigen::Vector3d p0 = Rcw * (Eigen::Vector3d(c.x, c.y, c.z) * B) + tcw;
      double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
      for (int k = 0; k < 8; ++k) {
        p[k] = p0 + double(k & 1) * ex + double((k >> 1) & 1) * ey + double(k >> 2) * ez;
        zmin = std::min(zmin, p[k].z());
        zmax = std::max(zmax, p[k].z());
      }
      if (zmax < near_m || zmin > far_m) continue;
      // Bounding box of the projection of the block's part in front of the near plane: the projections of its
      // corners in front and of the points where its edges cross the plane (a convex polytope in front of the
      // camera projects to the convex hull of its vertices' projections).
      double umin = std::numeric_limits<double>::infinity(), umax = -umin, vmin = umin, vmax = -umin;
      auto add = [&](const Eigen::Vector3d& q) {
        const double u = camera.fx * q.x() / q.z() + camera.cx, v = camera.fy * q.y() / q.z() + camera.cy;
        umin = std::min(umin, u), umax = std::max(umax, u);
        vmin = std::min(vmin, v), vmax = std::max(vmax, v);
      };
      for (int k = 0; k < 8; ++k) {
        if (p[k].z() >= near_m) add(p[k]);
        for (int axis = 0; axis < 3; ++axis) {
          const int j = k | (1 << axis);
          if (j == k) continue;  // each edge once, from its lower corner
          const double za = p[k].z() - near_m, zb = p[j].z() - near_m;
          if ((za < 0.0) != (zb < 0.0)) {
            Eigen::Vector3d q = p[k] + (za / (za - zb)) * (p[j] - p[k]);
            q.z() = near_m;
            add(q);
          }
        }
      }
      // Pixel x's ray passes through u = x; one pixel of slack covers rounding.
      if (umax < -1.0 || vmax < -1.0 || umin > W || vmin > H) continue;
      const int tx0 = std::max(0, int(std::floor(umin - 1.0)) / kTile);
      const int tx1 = std::min(TW - 1, int(std::min(std::ceil(umax + 1.0), double(W))) / kTile);
      const int ty0 = std::max(0, int(std::floor(vmin - 1.0)) / kTile);
      const int ty1 = std::min(TH - 1, int(std::min(std::ceil(vmax + 1.0), double(H))) / kTile);
      const float zn = float(std::max(zmin, near_m)), zf = float(zmax);
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) {
          float& n = tile_near[size_t(ty) * TW + tx];
          float& f = tile_far[size_t(ty) * TW + tx];
          n = std::min(n, zn);
          f = std::max(f, zf);
        }
    }
  }

  // One pixel: march its ray, then fill the outputs; true at a hit.
  auto cast_pixel = [&](VolumeSampler& sampler, int x, int y) -> bool {
    const Eigen::Vector3f d_cam(float((x - camera.cx) / camera.fx), float((y - camera.cy) / camera.fy), 1.0f);
    const float len = d_cam.norm();
    const Eigen::Vector3f u_world = R * (d_cam / len);
    const Eigen::Vector3f d_vox = u_world / float(voxel_m);
    Hit hit;
    bool found = false;
    const float hint = hint_image != nullptr ? (*hint_image)(x, y) : 0.0f;
    if (hint > 0.0f && std::isfinite(hint)) {
      // The bracket around the depth this frame measured: a + to - crossing there is the surface.
      const float w = hf_raycast_hint_halfwidth(hint, mu_m, float(voxel_m));
      const float z0 = std::max(float(options.min_depth_m), hint - w);
      const float z1 = std::min(float(options.max_depth_m), hint + w);
      found = z0 < z1 && march(sampler, o_vox, d_vox, z0 * len, z1 * len, mu_m, step_fraction, min_step_m,
                               float(voxel_m), refine_tol_m, &hit);
    }
    if (!found) {
      const size_t tile = size_t(y / kTile) * TW + size_t(x / kTile);
      // One voxel of slack on both sides covers float rounding of the corner projections.
      const float z0 = std::max(float(options.min_depth_m), tile_near[tile] - float(voxel_m));
      const float z1 = std::min(float(options.max_depth_m), tile_far[tile] + float(voxel_m));
      found = z0 < z1 && march(sampler, o_vox, d_vox, z0 * len, z1 * len, mu_m, step_fraction, min_step_m,
                               float(voxel_m), refine_tol_m, &hit);
    }
    if (!found) {
      out->depth(x, y) = 0.0f;
      out->vertices(x, y) = hf_invalid4();
      out->normals(x, y) = hf_invalid4();
      out->color(x, y) = Rgb8{};
      if (options.shade) out->shaded(x, y) = Rgb8{};
      return false;
    }
    const float z = hit.t / len;
    out->depth(x, y) = z;
    out->vertices(x, y) = hf_make_float4(d_cam.x() * z, d_cam.y() * z, z, 1.0f);
    float s = 0.0f;
    Eigen::Vector3f rgb(0.0f, 0.0f, 0.0f);
    if (options.color && sampler.sdf_color(hit.p_vox, &s, &rgb)) {
      auto to8 = [](float c) { return std::uint8_t(std::clamp(c + 0.5f, 0.0f, 255.0f)); };
      out->color(x, y) = Rgb8{to8(rgb.x()), to8(rgb.y()), to8(rgb.z())};
    } else {
      out->color(x, y) = Rgb8{};
    }
    Eigen::Vector3f n_world;
    if (sampler.normal(hit.p_vox, &n_world)) {
      const Eigen::Vector3f n = R_cw * n_world;
      out->normals(x, y) = hf_make_float4(n.x(), n.y(), n.z(), 1.0f);
      if (options.shade) {
        const hf_float4 to_cam = hf_make_float4(-d_cam.x() / len, -d_cam.y() / len, -1.0f / len, 0.0f);
        const auto g = std::uint8_t(255.0f * hf_headlight_shade(out->normals(x, y), to_cam) + 0.5f);
        out->shaded(x, y) = Rgb8{g, g, g};
      }
    } else {
      out->normals(x, y) = hf_invalid4();
      if (options.shade) out->shaded(x, y) = Rgb8{40, 40, 40};
    }
    return true;
  };

  // Parallel over 16 x 16 pixel tiles rather than rows: neighbouring rays read the same voxels and find them still
  // in cache (the march is bound by memory latency, not arithmetic). Each pixel is written once: deterministic.
  constexpr int kWork = 16;
  const int WX = (W + kWork - 1) / kWork, WY = (H + kWork - 1) / kWork;
  std::vector<int> tile_hits(size_t(WX) * WY, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, WX * WY), [&](const tbb::blocked_range<int>& work) {
    VolumeSampler sampler(lookup, options.min_weight);
    for (int wi = work.begin(); wi != work.end(); ++wi) {
      const int x0 = (wi % WX) * kWork, y0 = (wi / WX) * kWork;
      const int x1 = std::min(x0 + kWork, W), y1 = std::min(y0 + kWork, H);
      int hits = 0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) hits += cast_pixel(sampler, x, y) ? 1 : 0;
      tile_hits[size_t(wi)] = hits;
    }
  });
  int total = 0;
  for (int h : tile_hits) total += h;
  out->hit_count = total;
}

}  // namespace hf::fusion
