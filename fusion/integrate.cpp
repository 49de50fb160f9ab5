#include "fusion/integrate.h"

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <limits>

#include "core/parallel.h"
#include "core/simd_avx2.h"
#include "fusion/integrate_cpu.h"
#include "fusion/kernels/integrate_kernels.h"
#include "core/timing.h"

namespace hf::fusion {

namespace {

static_assert(sizeof(Rgb8) == 3, "colour pixels are packed RGB8");

// Block coordinates packed into 64 bits (21 bits each, +-2^20 blocks: +-10 km at 1 cm voxels) so the per-frame
// set of touched blocks can be sorted and deduplicated as plain integers.
constexpr int kCoordBias = 1 << 20;
std::uint64_t pack(int x, int y, int z) {
  return (std::uint64_t(x + kCoordBias) << 42) | (std::uint64_t(y + kCoordBias) << 21) | std::uint64_t(z + kCoordBias);
}
BlockCoord unpack(std::uint64_t k) {
  const std::uint64_t m = (1u << 21) - 1;
  return {int((k >> 42) & m) - kCoordBias, int((k >> 21) & m) - kCoordBias, int(k & m) - kCoordBias};
}

// Per-thread list of touched blocks with a direct-mapped cache: neighbouring pixels mostly cross the same blocks
// (a 8 cm block spans ~20 pixels at 2 m), so the cache removes most duplicates before the serial sort. 4096
// entries hold a frame's few thousand blocks (room, 1 cm: ~3 300) with few collisions; with 256 the sort got
// ~29 k keys for them and took 1.8-2.0 ms of the 6.6-7.1 ms allocation.
struct TouchedList {
  std::vector<std::uint64_t> keys;
  std::vector<std::uint64_t> cache = std::vector<std::uint64_t>(4096, ~std::uint64_t(0));
  void add(int x, int y, int z) {
    const std::uint64_t k = pack(x, y, z);
    std::uint64_t& slot = cache[(k * 0x9E3779B97F4A7C15ull) >> 52];
    if (slot == k) return;
    slot = k;
    keys.push_back(k);
  }
};

// Amanatides-Woo traversal of the unit grid (block units) from a to b, both inside the packable range.
// cell_a / cell_b are floor(a) / floor(b), already known to the caller.
void traverse(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3i& cell_a,
              const Eigen::Vector3i& cell_b, TouchedList& out) {
  int cell[3], end[3], step[3];
  double t_max[3], t_delta[3];
  const Eigen::Vector3d dir = b - a;
  for (int i = 0; i < 3; ++i) {
    cell[i] = cell_a[i];
    end[i] = cell_b[i];
    step[i] = dir[i] > 0 ? 1 : (dir[i] < 0 ? -1 : 0);
    if (step[i] == 0) {
      t_max[i] = t_delta[i] = std::numeric_limits<double>::infinity();
    } else {
      const double boundary = step[i] > 0 ? cell[i] + 1.0 : double(cell[i]);
      t_max[i] = (boundary - a[i]) / dir[i];
      t_delta[i] = 1.0 / std::abs(dir[i]);
    }
  }
  const int max_steps = std::abs(end[0] - cell[0]) + std::abs(end[1] - cell[1]) + std::abs(end[2] - cell[2]) + 1;
  for (int n = 0; n < max_steps; ++n) {
    out.add(cell[0], cell[1], cell[2]);
    const int axis = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
    if (t_max[axis] > 1.0) break;
    cell[axis] += step[axis];
    t_max[axis] += t_delta[axis];
  }
}

// True when some corner of the block lies in front of the camera and the corners' projections overlap the image.
bool block_in_view(const Eigen::Matrix3d& R_cw, const Eigen::Vector3d& t_cw, const Eigen::Vector3d& origin_world,
                   double block_m, const PinholeCamera& camera) {
  double u_min = 1e300, u_max = -1e300, v_min = 1e300, v_max = -1e300;
  bool any_in_front = false;
  for (int corner = 0; corner < 8; ++corner) {
    const Eigen::Vector3d p_world =
        origin_world + block_m * Eigen::Vector3d(corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
    const Eigen::Vector3d p = R_cw * p_world + t_cw;
    if (p.z() <= 1e-6) return true;  // straddles the camera plane: let the per-voxel test decide
    any_in_front = true;
    const Eigen::Vector2d px = camera.project(p);
    u_min = std::min(u_min, px.x());
    u_max = std::max(u_max, px.x());
    v_min = std::min(v_min, px.y());
    v_max = std::max(v_max, px.y());
  }
  return any_in_front && u_max >= -0.5 && v_max >= -0.5 && u_min < camera.width - 0.5 && v_min < camera.height - 0.5;
}

}  // namespace

namespace detail {

void check_frame_sizes(const DepthImage& depth, const ColorImage& colour, const PinholeCamera& camera) {
  if (depth.width() != camera.width || depth.height() != camera.height)
    throw Error("integrate: depth image is " + std::to_string(depth.width()) + "x" + std::to_string(depth.height()) +
                " but the camera is " + std::to_string(camera.width) + "x" + std::to_string(camera.height));
  if (!colour.empty() && (colour.width() != depth.width() || colour.height() != depth.height()))
    throw Error("integrate: colour image is " + std::to_string(colour.width()) + "x" +
                std::to_string(colour.height()) + " but the depth image is " + std::to_string(depth.width()) + "x" +
                std::to_string(depth.height()));
}

}  // namespace detail

std::vector<BlockCoord> blocks_touched_by(const VolumeParams& volume, const DepthImage& depth,
                                          const PinholeCamera& camera, const SE3& T_world_camera,
                                          const IntegrateParams& params, size_t* pixels_used) {
  detail::check_frame_sizes(depth, ColorImage(), camera);
  detail::BandFrame frame;
  const Eigen::Matrix3d R = T_world_camera.rotation();
  const Eigen::Vector3d t = T_world_camera.translation();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) frame.R[3 * i + j] = R(i, j);
    frame.t[i] = t[i];
  }
  frame.inv_block = 1.0 / volume.block_m();
  frame.mu = volume.truncation_m();
  frame.min_depth_m = params.min_depth_m;
  frame.max_depth_m = params.max_depth_m;
  const int W = depth.width();
  std::vector<double> ray_x(static_cast<size_t>(W));
  for (int u = 0; u < W; ++u) ray_x[size_t(u)] = (u - camera.cx) / camera.fx;
  const bool simd = cpu_has_avx2();

  // Per thread: the touched blocks, one row of band ends and two rows of their cells (this one and the one above).
  struct Scratch {
    TouchedList list;
    std::vector<double> ends;
    std::vector<std::int32_t> cells[2];
    std::vector<std::uint8_t> ok[2];
  };
  tbb::enumerable_thread_specific<Scratch> scratch;
  tbb::combinable<size_t> used([] { return size_t(0); });
  // Rows in fixed groups (not TBB's adaptive chunks): a pixel's traversal may be skipped for the row above's, so
  // the groups' borders must not depend on scheduling for the result to be deterministic.
  constexpr int kRowsPerGroup = 8;
  const int groups = (depth.height() + kRowsPerGroup - 1) / kRowsPerGroup;
  tbb::parallel_for(0, groups, [&](int g) {
    Scratch& s = scratch.local();
    s.ends.resize(6 * size_t(W));
    detail::BandRow band;
    for (int i = 0; i < 3; ++i) {
      band.a[i] = s.ends.data() + size_t(i) * W;
      band.b[i] = s.ends.data() + size_t(3 + i) * W;
    }
    for (int k = 0; k < 2; ++k) {
      s.cells[k].resize(6 * size_t(W));
      s.ok[k].assign(size_t(W), 0);  // no row above the group's first
    }
    size_t n = 0;
    const int v_end = std::min(depth.height(), (g + 1) * kRowsPerGroup);
    for (int v = g * kRowsPerGroup; v < v_end; ++v) {
      const int cur = v & 1;
      const std::int32_t* above = s.cells[1 - cur].data();
      const std::uint8_t* ok_above = s.ok[1 - cur].data();
      for (int i = 0; i < 3; ++i) {
        band.cell_a[i] = s.cells[cur].data() + size_t(i) * W;
        band.cell_b[i] = s.cells[cur].data() + size_t(3 + i) * W;
      }
      band.ok = s.ok[cur].data();
      const float* row = depth.data() + size_t(v) * W;
      const double ray_y = (v - camera.cy) / camera.fy;
      if (simd)
        detail::band_row_avx2(row, W, ray_x.data(), ray_y, frame, band);
      else
        detail::band_row(row, W, ray_x.data(), ray_y, frame, band);
      // A ray whose band starts and ends in the same blocks as its left or upper neighbour's crosses the same
      // blocks (the two segments are almost parallel and a fraction of a block apart): skip its traversal.
      const std::int32_t* here = s.cells[cur].data();
      auto same_ends = [W](const std::int32_t* a, int u_a, const std::int32_t* b, int u_b) {
        for (int i = 0; i < 6; ++i)
          if (a[size_t(i) * W + u_a] != b[size_t(i) * W + u_b]) return false;
        return true;
      };
      for (int u = 0; u < W; ++u) {
        if (!band.ok[u]) continue;
        ++n;
        if (u > 0 && band.ok[u - 1] && same_ends(here, u - 1, here, u)) continue;
        if (ok_above[u] && same_ends(above, u, here, u)) continue;
        traverse(Eigen::Vector3d(band.a[0][u], band.a[1][u], band.a[2][u]),
                 Eigen::Vector3d(band.b[0][u], band.b[1][u], band.b[2][u]),
                 Eigen::Vector3i(band.cell_a[0][u], band.cell_a[1][u], band.cell_a[2][u]),
                 Eigen::Vector3i(band.cell_b[0][u], band.cell_b[1][u], band.cell_b[2][u]), s.list);
      }
    }
    used.local() += n;
  });

  std::vector<std::uint64_t> keys;
  size_t total = 0;
  for (const auto& s : scratch) total += s.list.keys.size();
  keys.reserve(total);
  for (const auto& s : scratch) keys.insert(keys.end(), s.list.keys.begin(), s.list.keys.end());
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  std::vector<BlockCoord> coords(keys.size());
  for (size_t i = 0; i < keys.size(); ++i) coords[i] = unpack(keys[i]);
  if (pixels_used) *pixels_used = used.combine(std::plus<>());
  return coords;
}

namespace detail {

void update_blocks(VoxelUpdate op, const VolumeParams& volume,
                   const std::vector<std::pair<BlockCoord, VoxelBlock*>>& visible,
                   const std::vector<std::uint8_t*>& surface_free, const DepthImage& depth, const ColorImage& colour,
                   const PinholeCamera& camera, const SE3& T_world_camera, const IntegrateParams& params,
                   IntegrateStats* stats) {
  check_frame_sizes(depth, colour, camera);
  const auto t0 = std::chrono::steady_clock::now();
  const SE3 T_camera_world = T_world_camera.inverse();
  const Eigen::Matrix3d R_cw = T_camera_world.rotation();
  const Eigen::Vector3d t_cw = T_camera_world.translation();
  const double voxel_m = volume.voxel_m;
  // The camera-frame images of one voxel step along the world axes, shared by all blocks.
  BlockFrame steps{};
  for (int a = 0; a < 3; ++a) {
    steps.s_x[a] = float(R_cw(a, 0) * voxel_m);
    steps.s_y[a] = float(R_cw(a, 1) * voxel_m);
    steps.s_z[a] = float(R_cw(a, 2) * voxel_m);
  }
  const hf_intrinsics K = camera.kernel_intrinsics();
  const float mu = float(volume.truncation_m());
  const float* depth_px = depth.data();
  // Per-pixel point-to-plane factor (|cos theta| |(x/z, y/z, 1)|, 0 = unknown), from the shared kernel. Neighbours
  // more than mu apart in depth are a depth edge: beyond the band the two surfaces' voxels do not mix.
  std::vector<float> incidence;
  if (params.point_to_plane) {
    const auto t_inc = std::chrono::steady_clock::now();
    const int W = depth.width();
    incidence.resize(size_t(W) * depth.height());
    parallel_for_rows(depth.height(), [&](int v) {
      float* out = incidence.data() + size_t(v) * W;
      for (int u = 0; u < W; ++u) out[u] = hf_point_to_plane_factor(depth_px, u, v, K, mu);
    });
    stats->incidence_ms = ms_since(t_inc);
  }

  // Per-pixel factors of the depth (empty when off): the truncation band following the depth noise
  // (hf_truncation_scale) and the observation weight of far pixels (hf_weight_scale).
  auto per_pixel = [&](auto&& factor) {
    const int W = depth.width();
    std::vector<float> out(size_t(W) * depth.height());
    parallel_for_rows(depth.height(), [&](int v) {
      const size_t row = size_t(v) * W;
      for (int u = 0; u < W; ++u) out[row + u] = factor(depth_px[row + u]);
    });
    return out;
  };
  std::vector<float> mu_scale, w_scale;
  if (params.truncation_depth_ref_m > 0.0f)
    mu_scale = per_pixel([&](float z) {
      return hf_truncation_scale(params.truncation_depth_ref_m, params.truncation_min_fraction, z);
    });
  if (params.weight_depth_ref_m > 0.0f)
    w_scale = per_pixel([&](float z) { return hf_weight_scale(params.weight_depth_ref_m, z); });

  FrameInputs frame;
  frame.depth = depth_px;
  frame.w_scale = w_scale.empty() ? nullptr : w_scale.data();
  frame.incidence = incidence.empty() ? nullptr : incidence.data();
  frame.mu_scale = mu_scale.empty() ? nullptr : mu_scale.data();
  frame.rgb = colour.empty() ? nullptr : reinterpret_cast<const hf_uint8*>(colour.data());
  frame.K = K;
  frame.mu = mu;
  frame.max_weight = volume.max_weight;
  frame.w = params.observation_weight;
  // The AVX2 spellings have no per-pixel truncation or weight: the plain loops (the specification) when one is on.
  const bool simd = cpu_has_avx2() && size_t(depth.width()) * size_t(depth.height()) >= 2 && mu_scale.empty() &&
                    w_scale.empty();

  tbb::combinable<size_t> updated([] { return size_t(0); });
  tbb::combinable<size_t> in_view([] { return size_t(0); });
  tbb::parallel_for(tbb::blocked_range<size_t>(0, visible.size(), 16), [&](const tbb::blocked_range<size_t>& r) {
    size_t n_updated = 0, n_view = 0;
    for (size_t i = r.begin(); i != r.end(); ++i) {
      const BlockCoord& c = visible[i].first;
      const Eigen::Vector3d origin_world = Eigen::Vector3d(c.x, c.y, c.z) * volume.block_m();
      if (!block_in_view(R_cw, t_cw, origin_world, volume.block_m(), camera)) continue;
      ++n_view;
      BlockFrame b = steps;
      const Eigen::Vector3f p0 =
          (R_cw * (origin_world + Eigen::Vector3d::Constant(0.5 * voxel_m)) + t_cw).cast<float>();
      for (int a = 0; a < 3; ++a) b.p0[a] = p0[a];
      Voxel* voxels = visible[i].second->voxels.data();
      if (op == VoxelUpdate::deintegrate) {
        // Taking an observation out can move a voxel to either side of the surface: scan the block.
        const int n = simd ? deintegrate_block_avx2(voxels, b, frame) : deintegrate_block(voxels, b, frame);
        if (n > 0) *surface_free[i] = block_is_surface_free(*visible[i].second) ? 1 : 0;
        n_updated += size_t(n);
        continue;
      }
      bool wrote_surface = false;
      const int n = simd ? update_block_avx2(voxels, b, frame, &wrote_surface)
                         : update_block(voxels, b, frame, &wrote_surface);
      // The raycast's block skip (VoxelBlockGrid::surface_free) for a block this frame changed: a voxel written on
      // or behind a surface clears it; a block that was free and got only values in front of a surface stays free;
      // otherwise (this frame may have carved the block's last surface voxel away) the block is scanned.
      if (n > 0) {
        std::uint8_t& flag = *surface_free[i];
        if (wrote_surface)
          flag = 0;
        else if (flag == 0)
          flag = block_is_surface_free(*visible[i].second) ? 1 : 0;
      }
      n_updated += size_t(n);
    }
    updated.local() += n_updated;
    in_view.local() += n_view;
  });
  stats->update_ms = ms_since(t0);
  stats->voxels_updated = updated.combine(std::plus<>());
  stats->blocks_visible = in_view.combine(std::plus<>());
}

}  // namespace detail

IntegrateStats integrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                         const PinholeCamera& camera, const SE3& T_world_camera, const IntegrateParams& params,
                         BlockStore* store) {
  detail::check_frame_sizes(depth, colour, camera);
  IntegrateStats stats;
  const VolumeParams& volume = grid.params();
  grid.free_retired_tables();  // the grid is ours alone here: no reader can still probe the arrays growth retired

  // Phase 1: allocation along the rays' truncation bands.
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<BlockCoord> touched = blocks_touched_by(volume, depth, camera, T_world_camera, params,
                                                            &stats.pixels_used);
  std::vector<std::pair<BlockCoord, VoxelBlock*>> visible;
  std::vector<std::uint8_t*> surface_free;  // each visible block's flag (VoxelBlockGrid::surface_free)
  visible.reserve(touched.size());
  surface_free.reserve(touched.size());
  for (const BlockCoord& c : touched) {
    bool created = false;
    std::uint8_t* flag = nullptr;
    VoxelBlock* block = grid.allocate(c, &created, &flag);
    surface_free.push_back(flag);
    if (created) {
      ++stats.blocks_allocated;
      if (store && store->take(c, block)) ++stats.blocks_streamed_in;
    }
    visible.emplace_back(c, block);
  }
  stats.allocate_ms = ms_since(t0);

  // Phase 2: per-voxel update, parallel over blocks.
  detail::update_blocks(detail::VoxelUpdate::integrate, volume, visible, surface_free, depth, colour, camera,
                        T_world_camera, params, &stats);
  stats.blocks_total = grid.block_count();
  stats.memory_bytes = grid.memory_bytes();
  return stats;
}

}  // namespace hf::fusion
