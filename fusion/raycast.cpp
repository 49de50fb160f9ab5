#include "fusion/raycast.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
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
  for (const auto& [c, block] : blocks) {
    if (block == nullptr) throw Error("BlockLookup: null block pointer");
    size_t i = BlockCoordHash{}(c)&mask_;
    while (slots_[i].block != nullptr && !(slots_[i].x == c.x && slots_[i].y == c.y && slots_[i].z == c.z))
      i = (i + 1) & mask_;
    if (slots_[i].block != nullptr) {
      --size_;  // the same coordinate twice: the first one wins
      continue;
    }
    slots_[i] = Slot{c.x, c.y, c.z, block};
  }
}

// ---------------------------------------------------------------------------------------------------------------
// VolumeSampler

VolumeSampler::VolumeSampler(const BlockLookup& lookup, float min_weight)
    : lookup_(&lookup), min_weight_raw_(hf_quantise_weight(std::max(0.0f, min_weight))) {}

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

bool VolumeSampler::sdf(const Eigen::Vector3f& p_vox, float* out) {
  const Voxel* v[8];
  float f[3];
  if (!corners(p_vox, v, f)) return false;
  *out = hf_trilinear(hf_voxel_sdf(*v[0]), hf_voxel_sdf(*v[1]), hf_voxel_sdf(*v[2]), hf_voxel_sdf(*v[3]),
                      hf_voxel_sdf(*v[4]), hf_voxel_sdf(*v[5]), hf_voxel_sdf(*v[6]), hf_voxel_sdf(*v[7]), f[0], f[1],
                      f[2]);
  return true;
}

bool VolumeSampler::sdf_color(const Eigen::Vector3f& p_vox, float* out, Eigen::Vector3f* rgb) {
  const Voxel* v[8];
  float f[3];
  if (!corners(p_vox, v, f)) return false;
  *out = hf_trilinear(hf_voxel_sdf(*v[0]), hf_voxel_sdf(*v[1]), hf_voxel_sdf(*v[2]), hf_voxel_sdf(*v[3]),
                      hf_voxel_sdf(*v[4]), hf_voxel_sdf(*v[5]), hf_voxel_sdf(*v[6]), hf_voxel_sdf(*v[7]), f[0], f[1],
                      f[2]);
  auto channel = [&](auto get) {
    return hf_trilinear(float(get(v[0])), float(get(v[1])), float(get(v[2])), float(get(v[3])), float(get(v[4])),
                        float(get(v[5])), float(get(v[6])), float(get(v[7])), f[0], f[1], f[2]);
  };
  *rgb = Eigen::Vector3f(channel([](const Voxel* x) { return x->r; }), channel([](const Voxel* x) { return x->g; }),
                         channel([](const Voxel* x) { return x->b; }));
  return true;
}

bool VolumeSampler::normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox) {
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
bool march(VolumeSampler& sampler, const BlockLookup& lookup, const Eigen::Vector3f& o_vox,
           const Eigen::Vector3f& d_vox, float t_min, float t_max, float mu_m, float step_fraction, float min_step_m,
           float voxel_m, Hit* hit) {
  // Block b holds continuous voxel coordinates [8 b - 0.5, 8 b + 7.5).
  const Eigen::Vector3f inv_d(d_vox.x() != 0.0f ? 1.0f / d_vox.x() : std::numeric_limits<float>::infinity(),
                              d_vox.y() != 0.0f ? 1.0f / d_vox.y() : std::numeric_limits<float>::infinity(),
                              d_vox.z() != 0.0f ? 1.0f / d_vox.z() : std::numeric_limits<float>::infinity());
  const float skip_eps = 1e-3f * voxel_m;
  float t = t_min;
  bool have_prev = false;  // a valid sample with sdf > 0 precedes t
  float t_prev = 0.0f, s_prev = 0.0f;
  while (t < t_max) {
    const Eigen::Vector3f p = o_vox + t * d_vox;
    const Eigen::Vector3f q = (p.array() + 0.5f) * (1.0f / HF_BLOCK_SIZE);
    const float fbx = std::floor(q.x()), fby = std::floor(q.y()), fbz = std::floor(q.z());
    if (!(std::fabs(fbx) < 1e8f && std::fabs(fby) < 1e8f && std::fabs(fbz) < 1e8f)) return false;
    if (lookup.find(int(fbx), int(fby), int(fbz)) == nullptr) {
      // Jump to where the ray leaves this block.
      float t_exit = std::numeric_limits<float>::infinity();
      const float lo[3] = {fbx * HF_BLOCK_SIZE - 0.5f, fby * HF_BLOCK_SIZE - 0.5f, fbz * HF_BLOCK_SIZE - 0.5f};
      for (int a = 0; a < 3; ++a) {
        if (d_vox[a] == 0.0f) continue;
        const float plane = d_vox[a] > 0.0f ? lo[a] + HF_BLOCK_SIZE : lo[a];
        t_exit = std::min(t_exit, (plane - o_vox[a]) * inv_d[a]);
      }
      t = std::max(t_exit, t) + skip_eps;
      have_prev = false;
      continue;
    }
    float s = 0.0f;
    if (!sampler.sdf(p, &s)) {
      t += voxel_m;
      have_prev = false;
      continue;
    }
    if (s < 0.0f) {
      if (have_prev) {
        // + to - : refine on the bracket [t_prev, t] (linear interpolation, then regula falsi).
        float ta = t_prev, sa = s_prev, tb = t, sb = s;
        float tc = hf_zero_crossing(ta, sa, tb, sb);
        for (int it = 0; it < 2; ++it) {
          float sc = 0.0f;
          if (!sampler.sdf(o_vox + tc * d_vox, &sc)) break;
          if (sc > 0.0f) {
            ta = tc, sa = sc;
          } else if (sc < 0.0f) {
            tb = tc, sb = sc;
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
    have_prev = true;
    t_prev = t, s_prev = s;
    t += hf_raycast_step(s, mu_m, step_fraction, min_step_m);
  }
  return false;
}

}  // namespace

void raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
             const RaycastOptions& options, RaycastResult* out) {
  options.validate();
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
  std::vector<int> row_hits(H, 0);

  // Depth range per 8 x 8 pixel tile from the projected corners of every allocated block (InfiniTAM's range
  // image): a ray can only hit inside an allocated block, so it starts at the nearest block its tile sees and
  // stops after the farthest; tiles no block covers are not marched at all.
  constexpr int kTile = 8;
  const int TW = (W + kTile - 1) / kTile, TH = (H + kTile - 1) / kTile;
  std::vector<float> tile_near(size_t(TW) * TH, std::numeric_limits<float>::infinity());
  std::vector<float> tile_far(size_t(TW) * TH, 0.0f);
  {
    const SE3 T_camera_world = T_world_camera.inverse();
    const Eigen::Matrix3d Rcw = T_camera_world.rotation();
    const Eigen::Vector3d tcw = T_camera_world.translation();
    const double B = grid.params().block_m(), near_m = options.min_depth_m;
    for (const auto& [c, block] : grid.blocks()) {
      (void)block;
      double zmin = std::numeric_limits<double>::infinity(), zmax = -zmin;
      double umin = zmin, umax = -zmin, vmin = zmin, vmax = -zmin;
      bool behind = false;
      for (int k = 0; k < 8; ++k) {
        const Eigen::Vector3d p = Rcw * (Eigen::Vector3d(c.x + (k & 1), c.y + ((k >> 1) & 1), c.z + (k >> 2)) * B) + tcw;
        zmin = std::min(zmin, p.z());
        zmax = std::max(zmax, p.z());
        if (p.z() < near_m) {
          behind = true;
          continue;
        }
        const Eigen::Vector2d uv = camera.project(p);
        umin = std::min(umin, uv.x()), umax = std::max(umax, uv.x());
        vmin = std::min(vmin, uv.y()), vmax = std::max(vmax, uv.y());
      }
      if (zmax < near_m || zmin > options.max_depth_m) continue;
      int tx0 = 0, tx1 = TW - 1, ty0 = 0, ty1 = TH - 1;
      if (!behind) {  // a block reaching behind the near plane may cover any tile
        if (umax < -0.5 || vmax < -0.5 || umin > W - 0.5 || vmin > H - 0.5) continue;
        tx0 = std::max(0, int(std::floor(umin + 0.5)) / kTile), tx1 = std::min(TW - 1, int(std::floor(umax + 0.5)) / kTile);
        ty0 = std::max(0, int(std::floor(vmin + 0.5)) / kTile), ty1 = std::min(TH - 1, int(std::floor(vmax + 0.5)) / kTile);
      }
      for (int ty = ty0; ty <= ty1; ++ty)
        for (int tx = tx0; tx <= tx1; ++tx) {
          float& n = tile_near[size_t(ty) * TW + tx];
          float& f = tile_far[size_t(ty) * TW + tx];
          n = std::min(n, float(zmin));
          f = std::max(f, float(zmax));
        }
    }
  }

  parallel_for_rows(H, [&](int y) {
    VolumeSampler sampler(lookup, options.min_weight);
    int hits = 0;
    for (int x = 0; x < W; ++x) {
      const Eigen::Vector3f d_cam(float((x - camera.cx) / camera.fx), float((y - camera.cy) / camera.fy), 1.0f);
      const float len = d_cam.norm();
      const Eigen::Vector3f u_world = R * (d_cam / len);
      Hit hit;
      const size_t tile = size_t(y / kTile) * TW + size_t(x / kTile);
      // One voxel of slack on both sides covers float rounding of the corner projections.
      const float z0 = std::max(float(options.min_depth_m), tile_near[tile] - float(voxel_m));
      const float z1 = std::min(float(options.max_depth_m), tile_far[tile] + float(voxel_m));
      const bool found = z0 < z1 && march(sampler, lookup, o_vox, u_world / float(voxel_m), z0 * len, z1 * len, mu_m,
                                          step_fraction, min_step_m, float(voxel_m), &hit);
      if (!found) {
        out->depth(x, y) = 0.0f;
        out->vertices(x, y) = hf_invalid4();
        out->normals(x, y) = hf_invalid4();
        out->color(x, y) = Rgb8{};
        if (options.shade) out->shaded(x, y) = Rgb8{};
        continue;
      }
      ++hits;
      const float z = hit.t / len;
      out->depth(x, y) = z;
      out->vertices(x, y) = hf_make_float4(d_cam.x() * z, d_cam.y() * z, z, 1.0f);
      float s = 0.0f;
      Eigen::Vector3f rgb(0.0f, 0.0f, 0.0f);
      if (sampler.sdf_color(hit.p_vox, &s, &rgb)) {
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
    }
    row_hits[y] = hits;
  });
  int total = 0;
  for (int h : row_hits) total += h;
  out->hit_count = total;
}

}  // namespace hf::fusion
