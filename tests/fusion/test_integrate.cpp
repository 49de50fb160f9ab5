#include "fusion/integrate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "datasets/presets.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/deintegrate.h"
#include "fusion/kernels/integrate_kernels.h"
#include "fusion/volume_io.h"
#include "tests/common/analytic_depth.h"

namespace hf::fusion {
namespace {

using testing::render_plane_depth;
using testing::render_sphere_depth;

PinholeCamera small_camera() { return PinholeCamera::preset("ros").scaled(2); }  // 160x120

VolumeParams integrate_params_1cm(size_t capacity = 1 << 15) {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.truncation_vox = 4.0;
  p.capacity_blocks = capacity;
  return p;
}

// A synthetic sequence of a preset (with its sensor noise) seen by small_camera().
datasets::SyntheticSequence small_sequence(const std::string& preset, int frames) {
  datasets::SyntheticOptions options;
  options.preset = preset;
  options.frames = frames;
  options.camera = small_camera();
  return datasets::SyntheticSequence(options);
}

Eigen::Vector3d voxel_centre(const VolumeParams& p, const BlockCoord& c, int x, int y, int z) {
  return (Eigen::Vector3d(HF_BLOCK_SIZE * c.x + x, HF_BLOCK_SIZE * c.y + y, HF_BLOCK_SIZE * c.z + z) +
          Eigen::Vector3d::Constant(0.5)) *
         p.voxel_m;
}

// A fronto-parallel plane: the projective distance d - z equals the true signed distance, so every observed voxel
// must hold min(1, sdf / mu) up to the int16 step (and float rounding of the depth and the voxel position).
TEST(Integrate, FrontoParallelPlaneGivesAnalyticSdf) {
  const PinholeCamera camera = small_camera();
  const VolumeParams volume = integrate_params_1cm();
  VoxelBlockGrid grid(volume);
  const double plane_z = 1.2345;
  const SE3 T_world_camera = SE3::identity();
  const DepthImage depth = render_plane_depth(camera, T_world_camera, Eigen::Vector3d::UnitZ(), plane_z);
  const IntegrateStats stats = integrate(grid, depth, ColorImage(), camera, T_world_camera);
  EXPECT_GT(stats.blocks_allocated, 100u);
  EXPECT_EQ(stats.blocks_allocated, grid.block_count());
  EXPECT_GT(stats.voxels_updated, 0u);
  const double mu = volume.truncation_m();
  size_t checked = 0;
  double max_err = 0.0;
  for (const auto& [c, block] : grid.blocks()) {
    // Free space is never allocated: every block lies within the band |z - plane_z| <= mu (plus a block).
    const double block_z0 = c.z * volume.block_m();
    EXPECT_LE(block_z0, plane_z + mu);
    EXPECT_GE(block_z0 + volume.block_m(), plane_z - mu);
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          const Voxel& v = block->voxels[hf_voxel_index(x, y, z)];
          if (v.weight == 0) continue;
          const double expected = std::min(1.0, (plane_z - voxel_centre(volume, c, x, y, z).z()) / mu);
          ASSERT_GE(expected, -1.0 - 1e-6);
          max_err = std::max(max_err, std::abs(hf_voxel_sdf(v) - expected));
          EXPECT_EQ(hf_voxel_weight(v), 1.0f);
          ++checked;
        }
  }
  EXPECT_GT(checked, 10000u);
  // Bound: half an int16 step (1.5e-5) + float depth (1e-7 m) and float voxel positions (1e-7 m) over mu = 4 cm.
  EXPECT_LT(max_err, 0.5 / HF_SDF_SCALE + 2e-5) << "max error " << max_err;
}

// Calls fn(voxel, centre in the world, centre in the camera, u, w) for every observed voxel of grid whose centre
// projects into the camera's image at nearest pixel (u, w), skipping centres within float rounding of a pixel
// border (either pixel would be right there).
template <class Fn>
void for_each_observed_voxel(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_camera_world,
                             Fn fn) {
  for (const auto& [c, block] : grid.blocks()) {
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          const Voxel& v = block->voxels[hf_voxel_index(x, y, z)];
          if (v.weight == 0) continue;
          const Eigen::Vector3d p_world = voxel_centre(grid.params(), c, x, y, z);
          const Eigen::Vector3d p = T_camera_world * p_world;
          const Eigen::Vector2d px = camera.project(p);
          const double fu = px.x() + 0.5 - std::floor(px.x() + 0.5), fv = px.y() + 0.5 - std::floor(px.y() + 0.5);
          if (fu < 1e-3 || fu > 1 - 1e-3 || fv < 1e-3 || fv > 1 - 1e-3) continue;
          fn(v, p_world, p, int(std::floor(px.x() + 0.5)), int(std::floor(px.y() + 0.5)));
        }
  }
}

// The scene of the tilted-plane tests: the plane n . p = offset (facing the camera) seen by a slightly rotated and
// shifted camera, and its rendered depth.
struct TiltedPlane {
  PinholeCamera camera = small_camera();
  Eigen::Vector3d n = Eigen::Vector3d(0.3, -0.2, -1.0).normalized();
  double offset = n.dot(Eigen::Vector3d(0.1, 0.0, 1.5));
  SE3 T_world_camera{Eigen::Matrix3d(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY())),
                     Eigen::Vector3d(0.05, -0.03, 0.0)};
  DepthImage depth = render_plane_depth(camera, T_world_camera, n, offset);
  // Integrates the depth (no colour) with projective or point-to-plane distances.
  void fuse(VoxelBlockGrid& grid, bool point_to_plane) const {
    IntegrateParams params;
    params.point_to_plane = point_to_plane;
    integrate(grid, depth, ColorImage(), camera, T_world_camera, params);
  }
};

// A tilted plane seen from an offset, rotated camera, projective distances (point_to_plane off): each observed voxel
// holds the projective TSDF
// min(1, (d(u) - z) / mu) with u the nearest pixel of the voxel centre and d(u) the exact ray-plane depth, and
// the sign of the stored value agrees with the true signed distance away from the surface.
TEST(Integrate, TiltedPlaneMatchesProjectiveTsdf) {
  const TiltedPlane plane;
  const VolumeParams volume = integrate_params_1cm();
  VoxelBlockGrid grid(volume);
  plane.fuse(grid, /*point_to_plane=*/false);
  const SE3 T_camera_world = plane.T_world_camera.inverse();
  const double mu = volume.truncation_m();
  size_t checked = 0;
  for_each_observed_voxel(grid, plane.camera, T_camera_world, [&](const Voxel& v, const Eigen::Vector3d& p_world,
                                                            const Eigen::Vector3d& p, int u, int w) {
    const double d = plane.depth(u, w);
    const double expected = std::min(1.0, (d - p.z()) / mu);
    EXPECT_NEAR(hf_voxel_sdf(v), expected, 0.5 / HF_SDF_SCALE + 5e-5);
    const double true_sdf = plane.n.dot(p_world) - plane.offset;  // positive on the camera side
    if (std::abs(true_sdf) > 0.5 * volume.voxel_m) {
      EXPECT_EQ(hf_voxel_sdf(v) > 0, true_sdf > 0);
    }
    ++checked;
  });
  EXPECT_GT(checked, 10000u);
}

// hf_point_to_plane_factor on a tilted plane seen by a rotated camera: |n . (x/z, y/z, 1)| (n the unit normal in the
// camera frame) at every pixel whose depth and neighbours are valid, by central differences inside and one-sided
// differences beside holes and depth jumps (exact for a plane either way); 0 on the border, on invalid pixels and
// where a direction has no usable neighbour.
TEST(Integrate, PointToPlaneFactorOfAPlane) {
  TiltedPlane plane;
  const PinholeCamera& camera = plane.camera;
  const hf_intrinsics K = camera.kernel_intrinsics();
  DepthImage& depth = plane.depth;
  const Eigen::Vector3d n = plane.T_world_camera.rotation().transpose() * plane.n;  // camera frame
  auto exact = [&](int u, int v) {
    return std::abs(n.dot(Eigen::Vector3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0)));
  };
  // Holes and edges: a hole at (50, 40); a NaN at (80, 60); a 0.5 m jump at (100, 70); both horizontal neighbours of
  // (120, 90) gone.
  const float mu = 0.04f;
  depth(50, 40) = 0.0f;
  depth(80, 60) = std::numeric_limits<float>::quiet_NaN();
  depth(100, 70) += 0.5f;
  depth(119, 90) = 0.0f;
  depth(121, 90) = 0.0f;
  double max_err = 0.0;
  int checked = 0;
  for (int v = 1; v < camera.height - 1; ++v)
    for (int u = 1; u < camera.width - 1; ++u) {
      const float f = hf_point_to_plane_factor(depth.data(), u, v, K, mu);
      const bool bad = (u == 50 && v == 40) || (u == 80 && v == 60) || (u == 100 && v == 70) || (u == 120 && v == 90) ||
                       depth(u, v) == 0.0f;
      if (bad) {
        EXPECT_EQ(f, 0.0f) << u << "," << v;
        continue;
      }
      max_err = std::max(max_err, std::abs(f - exact(u, v)));
      ++checked;
    }
  EXPECT_GT(checked, (camera.width - 2) * (camera.height - 2) - 10);
  // Float depth (1e-7 m) over 1-2 pixel baselines of ~1 cm: ~1e-5 relative.
  EXPECT_LT(max_err, 1e-4);
  // Oblique: below 1 on this plane (about 0.95 at the centre).
  EXPECT_LT(hf_point_to_plane_factor(depth.data(), 80, 61, K, mu), 0.99f);
  for (int u = 0; u < camera.width; ++u) {
    EXPECT_EQ(hf_point_to_plane_factor(depth.data(), u, 0, K, mu), 0.0f);
    EXPECT_EQ(hf_point_to_plane_factor(depth.data(), u, camera.height - 1, K, mu), 0.0f);
  }
  EXPECT_EQ(hf_point_to_plane_factor(depth.data(), 0, 50, K, mu), 0.0f);
  EXPECT_EQ(hf_point_to_plane_factor(depth.data(), camera.width - 1, 50, K, mu), 0.0f);
}

// The same tilted plane with point-to-plane distances: each observed voxel holds the true signed
// distance (not the projective one) of the point where its pixel's ray reaches the voxel's depth, min(1, sdf / mu)
// up to the factor's float error; against the voxel centre itself the difference is the lateral offset of that
// point (at most half a pixel in u and v) along the normal.
TEST(Integrate, TiltedPlaneGivesTrueDistanceWithPointToPlane) {
  const TiltedPlane plane;
  const VolumeParams volume = integrate_params_1cm();
  VoxelBlockGrid grid(volume);
  plane.fuse(grid, /*point_to_plane=*/true);
  const SE3 T_camera_world = plane.T_world_camera.inverse();
  const Eigen::Vector3d n_cam = T_camera_world.rotation() * plane.n;
  const double mu = volume.truncation_m();
  size_t checked = 0, below_projective = 0;
  double max_err = 0.0, max_lateral = 0.0;
  for_each_observed_voxel(grid, plane.camera, T_camera_world, [&](const Voxel& v, const Eigen::Vector3d& p_world,
                                                            const Eigen::Vector3d& p, int u, int w) {
    if (u < 1 || w < 1 || u >= plane.camera.width - 1 || w >= plane.camera.height - 1) return;  // border: projective
    // The point of pixel (u, w)'s ray at the voxel's depth, and its true signed distance.
    const Eigen::Vector3d q = plane.camera.backproject(u, w, p.z());
    const double sdf_q = plane.n.dot(plane.T_world_camera * q) - plane.offset;
    const double expected = std::clamp(sdf_q / mu, -1.0, 1.0);
    max_err = std::max(max_err, std::abs(hf_voxel_sdf(v) - expected));
    const double sdf_p = plane.n.dot(p_world) - plane.offset;
    // Lateral offset q - p: at most half a pixel in u and v at depth p.z, seen along the normal.
    const double lateral_bound =
        (std::abs(n_cam.x()) / plane.camera.fx + std::abs(n_cam.y()) / plane.camera.fy) * 0.5 * p.z() + 1e-6;
    max_lateral = std::max(max_lateral, std::abs(sdf_q - sdf_p) / lateral_bound);
    below_projective += std::abs(hf_voxel_sdf(v)) < 0.99 * std::min(1.0, std::abs(plane.depth(u, w) - p.z()) / mu);
    ++checked;
  });
  EXPECT_GT(checked, 10000u);
  // Half an int16 step + the factor's ~1e-5 relative error on distances up to a few mu.
  EXPECT_LT(max_err, 0.5 / HF_SDF_SCALE + 1e-4) << "max error " << max_err;
  EXPECT_LE(max_lateral, 1.0);
  // Oblique view: in the band, the true distance is shorter than the projective one.
  EXPECT_GT(below_projective, checked / 4);
}

// The 8-byte voxel against a float reference computing the same update on sample voxels through 12 noisy frames
// of the sphere preset: the SDF stays within (n + 1) / 4 int16 steps (each update rounds by at most half a step
// and the running average shrinks earlier errors), the weight is exact, the colour within (n + 1) / 4 + 1 levels.
TEST(Integrate, QuantisationCostsNoAccuracyAgainstFloatReference) {
  const datasets::SyntheticSequence seq = small_sequence("sphere", 12);
  const VolumeParams volume = integrate_params_1cm();
  VoxelBlockGrid grid(volume);
  const float mu = float(volume.truncation_m());

  struct Reference {
    int i, j, k;
    double D = 0, W = 0, r = 0, g = 0, b = 0;
    bool has_colour = false;
    bool ambiguous = false;
  };
  std::vector<Reference> refs;
  for (int f = 0; f < seq.size(); ++f) {
    const datasets::SyntheticFrame frame = seq.frame(f);
    IntegrateParams projective;  // the float reference below computes projective distances
    projective.point_to_plane = false;
    integrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera, projective);
    if (f == 0) {  // sample voxels near the surface seen by the first frame
      for (const auto& [c, block] : grid.blocks()) {
        for (int idx = 0; idx < HF_VOXELS_PER_BLOCK; idx += 37) {
          if (block->voxels[idx].weight == 0 || refs.size() >= 400) continue;
          const int x = idx % 8, y = (idx / 8) % 8, z = idx / 64;
          refs.push_back({8 * c.x + x, 8 * c.y + y, 8 * c.z + z});
        }
      }
      ASSERT_GT(refs.size(), 100u);
    }
    const SE3 T_camera_world = frame.T_world_camera.inverse();
    for (Reference& ref : refs) {
      const Eigen::Vector3d p = T_camera_world * ((Eigen::Vector3d(ref.i, ref.j, ref.k) + Eigen::Vector3d::Constant(0.5)) *
                                                  volume.voxel_m);
      if (p.z() <= 0) continue;
      const Eigen::Vector2d px = seq.camera().project(p) + Eigen::Vector2d(0.5, 0.5);
      const double fu = px.x() - std::floor(px.x()), fv = px.y() - std::floor(px.y());
      if (fu < 1e-3 || fu > 1 - 1e-3 || fv < 1e-3 || fv > 1 - 1e-3) ref.ambiguous = true;
      if (!(px.x() >= 0 && px.y() >= 0 && px.x() < seq.camera().width && px.y() < seq.camera().height)) continue;
      const int u = int(px.x()), v = int(px.y());
      const double d = frame.depth(u, v);
      if (!(d > 0)) continue;
      const double eta = d - p.z();
      if (eta < -mu) continue;
      if (std::abs(eta + mu) < 1e-5 || std::abs(eta - mu) < 1e-5) ref.ambiguous = true;
      const double tsdf = std::min(1.0, eta / mu);
      if (eta < mu) {  // colour shares the SDF weight once it has a sample
        const Rgb8 col = frame.color(u, v);
        const double Wc = ref.has_colour ? ref.W : 0.0;
        ref.r = (ref.r * Wc + col.r) / (Wc + 1);
        ref.g = (ref.g * Wc + col.g) / (Wc + 1);
        ref.b = (ref.b * Wc + col.b) / (Wc + 1);
        ref.has_colour = true;
      }
      ref.D = (ref.D * ref.W + tsdf) / (ref.W + 1);
      ref.W += 1;
    }
  }
  const double n = seq.size();
  size_t compared = 0;
  double max_steps = 0;
  for (const Reference& ref : refs) {
    if (ref.ambiguous) continue;
    const Voxel* v = grid.voxel(ref.i, ref.j, ref.k);
    ASSERT_NE(v, nullptr);
    EXPECT_EQ(hf_voxel_weight(*v), ref.W);
    const double steps = std::abs(hf_voxel_sdf(*v) - ref.D) * HF_SDF_SCALE;
    max_steps = std::max(max_steps, steps);
    EXPECT_LE(steps, (n + 1) / 4 + 0.1);
    if (ref.has_colour) {
      EXPECT_NEAR(v->r, ref.r, (n + 1) / 4 + 1);
      EXPECT_NEAR(v->g, ref.g, (n + 1) / 4 + 1);
      EXPECT_NEAR(v->b, ref.b, (n + 1) / 4 + 1);
    }
    ++compared;
  }
  EXPECT_GT(compared, 100u);
  // In metres the worst SDF difference is steps * mu / 32767: micrometres, against millimetres of sensor noise.
  EXPECT_LT(max_steps * volume.truncation_m() / HF_SDF_SCALE, 1e-5);
}

// Blocks follow surface area, not volume: a sphere of twice the radius seen from twice the distance (the same
// images up to scale) needs ~4x the blocks, far from the 8x of its bounding volume.
TEST(Integrate, MemoryGrowsWithSurfaceArea) {
  const PinholeCamera camera = small_camera();
  auto blocks_for = [&](double radius) {
    VoxelBlockGrid grid(integrate_params_1cm());
    std::vector<SE3> poses = datasets::hemisphere_poses(Eigen::Vector3d::Zero(), 3 * radius, 8);
    for (const SE3& T : datasets::ring_poses(Eigen::Vector3d::Zero(), 3 * radius, 4, -0.6)) poses.push_back(T);
    for (const SE3& T : poses)
      integrate(grid, render_sphere_depth(camera, T, Eigen::Vector3d::Zero(), radius), ColorImage(), camera, T);
    return double(grid.block_count());
  };
  const double small = blocks_for(0.4), large = blocks_for(0.8);
  const double ratio = large / small;
  EXPECT_GT(small, 200);
  EXPECT_GT(ratio, 3.0) << small << " -> " << large;
  EXPECT_LT(ratio, 5.0) << small << " -> " << large;
}

TEST(Integrate, InvalidDepthNeverAllocates) {
  const PinholeCamera camera = small_camera();
  VoxelBlockGrid grid(integrate_params_1cm());
  DepthImage depth(camera.width, camera.height, 0.0f);
  for (int v = 0; v < camera.height; ++v)
    for (int u = 0; u < camera.width; ++u) {
      const int kind = (u + v) % 5;
      depth(u, v) = kind == 0   ? std::numeric_limits<float>::quiet_NaN()
                    : kind == 1 ? std::numeric_limits<float>::infinity()
                    : kind == 2 ? -std::numeric_limits<float>::infinity()
                    : kind == 3 ? -1.0f
                                : 0.0f;
    }
  IntegrateStats stats = integrate(grid, depth, ColorImage(), camera, SE3::identity());
  EXPECT_EQ(grid.block_count(), 0u);
  EXPECT_EQ(stats.pixels_used, 0u);
  EXPECT_EQ(stats.voxels_updated, 0u);
  // Out of range (too near / too far) allocates nothing either.
  IntegrateParams params;
  depth = DepthImage(camera.width, camera.height, 0.05f);
  integrate(grid, depth, ColorImage(), camera, SE3::identity(), params);
  depth = DepthImage(camera.width, camera.height, 20.0f);
  integrate(grid, depth, ColorImage(), camera, SE3::identity(), params);
  EXPECT_EQ(grid.block_count(), 0u);
  // One valid pixel allocates only the blocks its band [d - mu, d + mu] crosses: at most 2 mu / block + 3.
  depth = DepthImage(camera.width, camera.height, 0.0f);
  depth(40, 30) = 1.5f;
  stats = integrate(grid, depth, ColorImage(), camera, SE3::identity());
  EXPECT_EQ(stats.pixels_used, 1u);
  EXPECT_GE(grid.block_count(), 1u);
  EXPECT_LE(grid.block_count(), 4u);
  for (const BlockCoord& c : grid.block_coords()) {
    const double z0 = c.z * grid.params().block_m();
    EXPECT_LE(z0, 1.5 + grid.params().truncation_m());
    EXPECT_GE(z0 + grid.params().block_m(), 1.5 - grid.params().truncation_m());
  }
}

TEST(Integrate, WeightCapAndColourAverage) {
  const PinholeCamera camera = small_camera();
  VolumeParams volume = integrate_params_1cm();
  volume.max_weight = 5.0f;
  VoxelBlockGrid grid(volume);
  const DepthImage depth = render_plane_depth(camera, SE3::identity(), Eigen::Vector3d::UnitZ(), 1.0);
  ColorImage red(camera.width, camera.height, Rgb8{200, 10, 30});
  ColorImage blue(camera.width, camera.height, Rgb8{0, 0, 250});
  for (int i = 0; i < 4; ++i) integrate(grid, depth, red, camera, SE3::identity());
  integrate(grid, depth, blue, camera, SE3::identity());
  size_t surface = 0;
  for (const auto& [c, block] : grid.blocks())
    for (const Voxel& v : block->voxels) {
      if (v.weight == 0) continue;
      EXPECT_EQ(hf_voxel_weight(v), 5.0f);
      if (std::abs(hf_voxel_sdf(v)) < 0.99f) {  // inside the band: colour is (4 red + 1 blue) / 5
        EXPECT_EQ(v.flags & HF_VOXEL_FLAG_COLOUR, HF_VOXEL_FLAG_COLOUR);
        EXPECT_EQ(v.r, 160);
        EXPECT_EQ(v.g, 8);
        EXPECT_EQ(v.b, 74);
        ++surface;
      }
    }
  EXPECT_GT(surface, 1000u);
  // Past the cap the weight stays at max_weight and the new observation counts 1 / (W_max + 1).
  for (int i = 0; i < 3; ++i) integrate(grid, depth, blue, camera, SE3::identity());
  for (const auto& [c, block] : grid.blocks())
    for (const Voxel& v : block->voxels)
      if (v.weight != 0) {
        ASSERT_EQ(hf_voxel_weight(v), 5.0f);
      }
}

TEST(Integrate, KernelRejectsBehindSurfaceAndUpdatesFreeSpace) {
  float depth[4] = {1.0f, 1.0f, 1.0f, 1.0f};
  const hf_intrinsics K{2.0f, 2.0f, 0.5f, 0.5f, 2, 2};
  hf_voxel v{};
  const float mu = 0.04f;
  EXPECT_EQ(hf_integrate_voxel(&v, hf_make_float4(0, 0, 1.05f, 1), depth, nullptr, nullptr, K, mu, 100.0f, 1.0f), 0);
  EXPECT_EQ(v.weight, 0);
  EXPECT_EQ(hf_integrate_voxel(&v, hf_make_float4(0, 0, -1.0f, 1), depth, nullptr, nullptr, K, mu, 100.0f, 1.0f), 0);
  EXPECT_EQ(hf_integrate_voxel(&v, hf_make_float4(0, 0, 0.5f, 1), depth, nullptr, nullptr, K, mu, 100.0f, 1.0f), 1);
  EXPECT_EQ(v.sdf, 32767);  // carved: truncated at +1
  EXPECT_EQ(v.flags, 0);    // no colour given
  EXPECT_EQ(hf_integrate_voxel(&v, hf_make_float4(0, 0, 1.02f, 1), depth, nullptr, nullptr, K, mu, 100.0f, 1.0f), 1);
  EXPECT_NEAR(hf_voxel_sdf(v), (1.0f - 0.5f) / 2, 1e-4f);
  EXPECT_EQ(hf_voxel_weight(v), 2.0f);
}

// Depth-dependent truncation (IntegrateParams::truncation_depth_ref_m): a fronto-parallel plane at depth z, so the
// projective distance is the true one. The band is mu_z = mu min(1, max(f, (z / ref)^2)); every observed voxel holds
// clamp(sdf, -mu_z, mu_z) / mu (the values stay in units of mu), none more than mu_z behind the plane is observed,
// and with the option off the same frame gives exactly today's field. Planes at 0.8 m and 1.6 m with ref 2 m and f
// 0.25 give bands of 0.25 mu (the floor: (0.4)^2 = 0.16) and 0.64 mu.
TEST(Integrate, DepthDependentTruncationFollowsTheFormula) {
  EXPECT_EQ(hf_truncation_scale(0.0f, 0.5f, 3.0f), 1.0f);  // off
  EXPECT_EQ(hf_truncation_scale(2.0f, 0.25f, 0.8f), 0.25f);
  EXPECT_FLOAT_EQ(hf_truncation_scale(2.0f, 0.25f, 1.6f), 0.64f);
  EXPECT_EQ(hf_truncation_scale(2.0f, 0.25f, 2.5f), 1.0f);
  const PinholeCamera camera = small_camera();
  const VolumeParams volume = integrate_params_1cm();
  const double mu = volume.truncation_m();
  for (const double plane_z : {0.8, 1.6}) {
    IntegrateParams params;
    params.truncation_depth_ref_m = 2.0f;
    params.truncation_min_fraction = 0.25f;
    const double s = std::min(1.0, std::max(0.25, (plane_z / 2.0) * (plane_z / 2.0)));
    const DepthImage depth = render_plane_depth(camera, SE3::identity(), Eigen::Vector3d::UnitZ(), plane_z);
    VoxelBlockGrid grid(volume), off(volume);
    integrate(grid, depth, ColorImage(), camera, SE3::identity(), params);
    integrate(off, depth, ColorImage(), camera, SE3::identity());
    size_t checked = 0, clamped = 0, hidden_now = 0;
    double max_err = 0.0;
    for (const auto& [c, block] : off.blocks()) {
      const VoxelBlock* b = grid.find(c);
      ASSERT_NE(b, nullptr);  // the allocation band is mu either way
      for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 8; ++y)
          for (int x = 0; x < 8; ++x) {
            const int i = hf_voxel_index(x, y, z);
            const double sdf = plane_z - voxel_centre(volume, c, x, y, z).z();
            const Voxel& v = b->voxels[i];
            if (block->voxels[i].weight == 0) {
              EXPECT_EQ(v.weight, 0);
              continue;
            }
            if (sdf < -s * mu - 1e-4) {  // behind the narrower band: no longer observed
              EXPECT_EQ(v.weight, 0) << sdf;
              ++hidden_now;
              continue;
            }
            if (std::abs(sdf + s * mu) < 1e-4) continue;  // on the band's edge: either side is right
            ASSERT_NE(v.weight, 0) << sdf;
            const double expected = std::clamp(sdf, -s * mu, s * mu) / mu;
            clamped += std::abs(sdf) > s * mu;
            max_err = std::max(max_err, std::abs(hf_voxel_sdf(v) - expected));
            ++checked;
          }
    }
    EXPECT_GT(checked, 5000u);
    EXPECT_GT(clamped, 1000u);
    EXPECT_GT(hidden_now, 1000u);
    // Bound as FrontoParallelPlaneGivesAnalyticSdf's: half an int16 step plus float depth and positions over mu.
    EXPECT_LT(max_err, 0.5 / HF_SDF_SCALE + 2e-5) << "plane at " << plane_z;
  }
}

// Observation weight by depth (IntegrateParams::weight_depth_ref_m): a fronto-parallel plane at depth d fused twice
// gives every observed voxel the weight 2 min(1, max(1/8, (ref / d)^2)) (exact in the 1/16 steps the weight is
// stored in for these d) and the same value as unweighted fusion; deintegrating one frame leaves one observation.
TEST(Integrate, DepthWeightFollowsTheFormula) {
  EXPECT_EQ(hf_weight_scale(0.0f, 3.0f), 1.0f);  // off
  EXPECT_EQ(hf_weight_scale(1.5f, 1.0f), 1.0f);
  EXPECT_EQ(hf_weight_scale(1.5f, 3.0f), 0.25f);
  EXPECT_EQ(hf_weight_scale(1.0f, 4.0f), 0.125f);  // (1/4)^2 = 1/16, floored
  const PinholeCamera camera = small_camera();
  const VolumeParams volume = integrate_params_1cm();
  for (const double plane_z : {1.0, 3.0}) {
    IntegrateParams params;
    params.weight_depth_ref_m = 1.5f;
    const float expected_w = 2.0f * hf_weight_scale(1.5f, float(plane_z));
    const DepthImage depth = render_plane_depth(camera, SE3::identity(), Eigen::Vector3d::UnitZ(), plane_z);
    VoxelBlockGrid grid(volume), off(volume);
    for (int i = 0; i < 2; ++i) {
      integrate(grid, depth, ColorImage(), camera, SE3::identity(), params);
      integrate(off, depth, ColorImage(), camera, SE3::identity());
    }
    size_t checked = 0;
    for (const auto& [c, block] : off.blocks()) {
      const VoxelBlock* b = grid.find(c);
      ASSERT_NE(b, nullptr);
      for (size_t i = 0; i < block->voxels.size(); ++i) {
        if (block->voxels[i].weight == 0) continue;
        ASSERT_EQ(hf_voxel_weight(b->voxels[i]), expected_w) << plane_z;
        ASSERT_EQ(b->voxels[i].sdf, block->voxels[i].sdf);
        ++checked;
      }
    }
    EXPECT_GT(checked, 5000u);
    deintegrate(grid, depth, ColorImage(), camera, SE3::identity(), params);
    for (const auto& [c, block] : grid.blocks())
      for (const Voxel& v : block->voxels)
        if (v.weight != 0) {
          ASSERT_EQ(hf_voxel_weight(v), expected_w / 2) << plane_z;
        }
  }
}

TEST(Integrate, ErrorsAndDeterminism) {
  const PinholeCamera camera = small_camera();
  VoxelBlockGrid grid(integrate_params_1cm(20));
  const DepthImage depth = render_plane_depth(camera, SE3::identity(), Eigen::Vector3d::UnitZ(), 1.0);
  EXPECT_THROW(integrate(grid, DepthImage(10, 10), ColorImage(), camera, SE3::identity()), Error);
  EXPECT_THROW(integrate(grid, depth, ColorImage(3, 3), camera, SE3::identity()), Error);
  try {
    integrate(grid, depth, ColorImage(), camera, SE3::identity());
    FAIL() << "expected CapacityError";
  } catch (const CapacityError& e) {
    EXPECT_NE(std::string(e.what()).find("capacity 20 blocks"), std::string::npos) << e.what();
  }
  // The same frames give the same bytes however TBB schedules the blocks.
  const datasets::SyntheticSequence seq = small_sequence("sphere", 3);
  std::string bytes[2];
  for (int run = 0; run < 2; ++run) {
    VoxelBlockGrid g(integrate_params_1cm());
    for (int f = 0; f < seq.size(); ++f) {
      const auto frame = seq.frame(f);
      integrate(g, frame.depth, frame.color, camera, frame.T_world_camera);
    }
    bytes[run] = serialize_volume(g);
  }
  EXPECT_EQ(bytes[0], bytes[1]);
}

// integrate() keeps every block's surface_free flag (the raycast's block skip) equal to what its voxels say:
// exact for every block with an observed voxel, false (never skip) for blocks no frame has observed yet. Over a
// noisy sequence both kinds of flag occur.
TEST(Integrate, SurfaceFreeFlagsMatchTheVoxels) {
  const datasets::SyntheticSequence seq = small_sequence("room", 12);
  VoxelBlockGrid grid(integrate_params_1cm());
  size_t free_blocks = 0, surface_blocks = 0;
  for (int f = 0; f < seq.size(); f += 3) {
    const auto frame = seq.frame(f);
    integrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera);
    for (const auto& [c, block] : grid.blocks()) {
      bool observed = false;
      for (const Voxel& v : block->voxels) observed |= v.weight > 0;
      const bool expected = observed && block_is_surface_free(*block);
      ASSERT_EQ(grid.surface_free(c), expected) << "frame " << f << ", block " << c.x << " " << c.y << " " << c.z;
      free_blocks += expected ? 1 : 0;
      surface_blocks += expected ? 0 : 1;
    }
  }
  EXPECT_GT(free_blocks, 100u);
  EXPECT_GT(surface_blocks, 100u);
}

// integrate()'s update loop (projections of a block row first, then the updates) must give exactly what the
// shared per-voxel kernel hf_integrate_voxel gives voxel by voxel (the OpenCL path will run the latter), with the
// voxel centres stepped through the block the same way.
TEST(Integrate, UpdateLoopMatchesPerVoxelKernelBitForBit) {
  const datasets::SyntheticSequence seq = small_sequence("sphere", 3);
  const VolumeParams volume = integrate_params_1cm();
  const hf_intrinsics K = seq.camera().kernel_intrinsics();
  const float mu = float(volume.truncation_m());
  // Both distances: projective (no factor map) and point-to-plane (the per-pixel factor map).
  for (const bool point_to_plane : {false, true}) {
    SCOPED_TRACE(point_to_plane ? "point-to-plane" : "projective");
    VoxelBlockGrid fast(volume), reference(volume);
    IntegrateParams params;
    params.point_to_plane = point_to_plane;
    size_t updated = 0;
    for (int f = 0; f < seq.size(); ++f) {
      const datasets::SyntheticFrame frame = seq.frame(f);
      integrate(fast, frame.depth, frame.color, seq.camera(), frame.T_world_camera, params);
      std::vector<float> factor;
      if (point_to_plane) {  // pixel by pixel with the shared function
        factor.resize(frame.depth.pixels().size());
        for (int v = 0; v < K.height; ++v)
          for (int u = 0; u < K.width; ++u)
            factor[size_t(v) * K.width + u] = hf_point_to_plane_factor(frame.depth.data(), u, v, K, mu);
      }
      const float* factor_px = factor.empty() ? nullptr : factor.data();
      const SE3 T_camera_world = frame.T_world_camera.inverse();
      const Eigen::Matrix3d R = T_camera_world.rotation();
      const Eigen::Vector3d t = T_camera_world.translation();
      const Eigen::Vector3f sx = (R.col(0) * volume.voxel_m).cast<float>(),
                            sy = (R.col(1) * volume.voxel_m).cast<float>(),
                            sz = (R.col(2) * volume.voxel_m).cast<float>();
      for (const BlockCoord& c : blocks_touched_by(volume, frame.depth, seq.camera(), frame.T_world_camera)) {
        VoxelBlock* block = reference.allocate(c);
        const Eigen::Vector3d origin = Eigen::Vector3d(c.x, c.y, c.z) * volume.block_m();
        const Eigen::Vector3f p0 =
            (R * (origin + Eigen::Vector3d::Constant(0.5 * volume.voxel_m)) + t).cast<float>();
        for (int z = 0; z < 8; ++z) {
          const Eigen::Vector3f pz = p0 + float(z) * sz;
          for (int y = 0; y < 8; ++y) {
            const Eigen::Vector3f row = pz + float(y) * sy;
            for (int x = 0; x < 8; ++x) {
              const Eigen::Vector3f p = row + float(x) * sx;
              updated += hf_integrate_voxel(&block->voxels[hf_voxel_index(x, y, z)],
                                            hf_make_float4(p.x(), p.y(), p.z(), 1.0f), frame.depth.data(), factor_px,
                                            reinterpret_cast<const hf_uint8*>(frame.color.data()), K, mu,
                                            volume.max_weight, 1.0f);
            }
          }
        }
      }
    }
    EXPECT_GT(updated, 50000u);
    ASSERT_EQ(fast.block_coords(), reference.block_coords());
    size_t differing = 0;
    for (const BlockCoord& c : fast.block_coords())
      differing +=
          std::memcmp(fast.find(c)->voxels.data(), reference.find(c)->voxels.data(), sizeof(VoxelBlock)) != 0;
    EXPECT_EQ(differing, 0u);
  }
}

}  // namespace
}  // namespace hf::fusion
