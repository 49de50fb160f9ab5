// Raycasting analytic volumes: depth, vertices, normals and colour against the exact surface; block skipping,
// back faces, empty volumes and bad options.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <random>
#include <set>
#include <tuple>
#include <utility>
#include <vector>

#include <tbb/global_control.h>

#include "core/error.h"
#include "datasets/presets.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "fusion/kernels/raycast_kernels.h"
#include "fusion/raycast.h"
#include "fusion/raycast_sampled.h"
#include "tests/common/analytic_depth.h"

namespace hf::fusion {
namespace {

using RaycastSdfFn = std::function<double(const Eigen::Vector3d&)>;

void fill_raycast_sdf(VoxelBlockGrid& grid, const RaycastSdfFn& sdf, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
          Rgb8 colour = Rgb8{200, 100, 50}) {
  const double v = grid.params().voxel_m, mu = grid.params().truncation_m(), B = grid.params().block_m();
  const BlockCoord a = grid.block_of(lo), b = grid.block_of(hi);
  for (int bz = a.z; bz <= b.z; ++bz)
    for (int by = a.y; by <= b.y; ++by)
      for (int bx = a.x; bx <= b.x; ++bx) {
        const Eigen::Vector3d centre = (Eigen::Vector3d(bx, by, bz) + Eigen::Vector3d::Constant(0.5)) * B;
        if (std::abs(sdf(centre)) > mu + B) continue;
        VoxelBlock* block = grid.allocate({bx, by, bz});
        for (int z = 0; z < 8; ++z)
          for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
              const Eigen::Vector3d p = (Eigen::Vector3d(8 * bx + x, 8 * by + y, 8 * bz + z) +
                                         Eigen::Vector3d::Constant(0.5)) * v;
              Voxel& vox = block->voxels[hf_voxel_index(x, y, z)];
              vox.sdf = hf_quantise_sdf(float(std::clamp(sdf(p) / mu, -1.0, 1.0)));
              vox.weight = hf_quantise_weight(1.0f);
              vox.r = colour.r, vox.g = colour.g, vox.b = colour.b;
            }
      }
}

VolumeParams raycast_params_1cm() {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.capacity_blocks = 1 << 15;
  return p;
}

const PinholeCamera kCamera = PinholeCamera::preset("ros").scaled(2);  // 160 x 120

// Fuses frames 0, step, 2 step, ... below `frames` of the room preset (Kinect-like noise) seen by kCamera into grid;
// returns the last frame fused.
datasets::SyntheticFrame fuse_noisy_room(VoxelBlockGrid& grid, int frames, int step) {
  datasets::SyntheticOptions o;
  o.preset = "room";
  o.frames = frames;
  o.camera = kCamera;
  const datasets::SyntheticSequence seq(o);
  datasets::SyntheticFrame f;
  for (int i = 0; i < frames; i += step) {
    f = seq.frame(i);
    integrate(grid, f.depth, f.color, seq.camera(), f.T_world_camera);
  }
  return f;
}

TEST(RaycastKernels, TrilinearAndZeroCrossing) {
  // A linear function is reproduced exactly.
  auto f = [](float x, float y, float z) { return 0.3f + 0.5f * x - 0.25f * y + 0.125f * z; };
  EXPECT_FLOAT_EQ(hf_trilinear(f(0, 0, 0), f(1, 0, 0), f(0, 1, 0), f(1, 1, 0), f(0, 0, 1), f(1, 0, 1), f(0, 1, 1),
                               f(1, 1, 1), 0.25f, 0.5f, 0.75f),
                  f(0.25f, 0.5f, 0.75f));
  EXPECT_FLOAT_EQ(hf_zero_crossing(1.0f, 0.5f, 2.0f, -1.5f), 1.25f);
  EXPECT_FLOAT_EQ(hf_raycast_step(0.5f, 0.04f, 0.8f, 0.001f), 0.016f);
  EXPECT_FLOAT_EQ(hf_raycast_step(0.001f, 0.04f, 0.8f, 0.005f), 0.005f);
  EXPECT_FALSE(hf_is_valid4(hf_normal_from_differences(0.0f, 0.0f, 0.0f)));
  const hf_float4 n = hf_normal_from_differences(3.0f, 0.0f, -4.0f);
  EXPECT_FLOAT_EQ(n.x, 0.6f);
  EXPECT_FLOAT_EQ(n.z, -0.8f);
}

TEST(Raycast, SphereMatchesAnalyticDepthNormalsAndColour) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  const double r = 0.4;
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - r; }, c.array() - 0.5, c.array() + 0.5,
       Rgb8{10, 20, 30});
  const SE3 T_world_camera = datasets::look_at({1.3, -0.4, 0.5}, c);
  const RaycastResult out = raycast(grid, kCamera, T_world_camera);
  const DepthImage truth = testing::render_sphere_depth(kCamera, T_world_camera, c, r);
  ASSERT_EQ(out.depth.width(), kCamera.width);
  int both = 0, miss = 0;
  double sq = 0.0, worst = 0.0, normal_sq = 0.0;
  const Eigen::Matrix3d R = T_world_camera.rotation();
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      const float d = out.depth(x, y), t = truth(x, y);
      if (t == 0.0f) {
        EXPECT_EQ(d, 0.0f) << x << "," << y;
        continue;
      }
      if (d == 0.0f) {
        ++miss;  // only grazing rays at the silhouette may miss
        continue;
      }
      ++both;
      const double err = double(d) - double(t);
      sq += err * err;
      worst = std::max(worst, std::abs(err));
      const hf_float4 v = out.vertices(x, y), n = out.normals(x, y);
      ASSERT_EQ(v.w, 1.0f);
      EXPECT_FLOAT_EQ(v.z, d);
      ASSERT_EQ(n.w, 1.0f);
      const Eigen::Vector3d p_world = T_world_camera * Eigen::Vector3d(v.x, v.y, v.z);
      const Eigen::Vector3d n_true = (p_world - c).normalized();
      const Eigen::Vector3d n_world = R * Eigen::Vector3d(n.x, n.y, n.z);
      const double ang = std::acos(std::clamp(n_true.dot(n_world), -1.0, 1.0));
      normal_sq += ang * ang;
      EXPECT_EQ(out.color(x, y), (Rgb8{10, 20, 30}));
      EXPECT_GT(out.shaded(x, y).r, 0);
    }
  ASSERT_GT(both, 3000);
  EXPECT_LT(miss, both / 50);
  EXPECT_EQ(out.hit_count, both);
  // Depth along the ray at a 1 cm grid: trilinear interpolation of an exact SDF is within h^2/(8r) of the surface.
  EXPECT_LT(std::sqrt(sq / both), 0.05 * 0.01);
  EXPECT_LT(worst, 0.3 * 0.01);
  EXPECT_LT(std::sqrt(normal_sq / both) * 180.0 / M_PI, 1.0);
}

TEST(Raycast, TiltedPlaneAcrossManyBlocksAndFarAway) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d n = Eigen::Vector3d(0.1, 0.2, 1.0).normalized();
  const double offset = -0.0137;
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return n.dot(p) - offset; }, {-1.5, -1.5, -0.5}, {1.5, 1.5, 0.5});
  // Camera 1.2 m above, looking down obliquely, plus a camera 3 m away along the plane normal.
  for (const SE3& T : {datasets::look_at({0.3, -0.5, 1.2}, {0.0, 0.1, 0.0}), datasets::look_at({0.0, 0.0, 3.0}, {0.1, 0.0, 0.0})}) {
    const RaycastResult out = raycast(grid, kCamera, T);
    const DepthImage truth = testing::render_plane_depth(kCamera, T, n, offset);
    int hits = 0, expected = 0, bad_normals = 0;
    for (int y = 0; y < kCamera.height; ++y)
      for (int x = 0; x < kCamera.width; ++x) {
        const Eigen::Vector3d p_true = T * kCamera.backproject(x, y, truth(x, y));
        // Well inside the filled 3 x 3 m patch every ray must hit.
        if (truth(x, y) > 0.0f && std::abs(p_true.x()) < 1.4 && std::abs(p_true.y()) < 1.4) ++expected;
        if (out.depth(x, y) == 0.0f) continue;
        ++hits;
        // A linear SDF: exact up to float rounding of the ray (t ~ metres, float eps 1e-7 relative).
        EXPECT_NEAR(out.depth(x, y), truth(x, y), 1e-4) << x << "," << y;
        const hf_float4 nc = out.normals(x, y);
        if (nc.w == 0.0f) {
          ++bad_normals;  // only at the rim of the filled patch, where a gradient sample is unobserved
          continue;
        }
        const Eigen::Vector3d nw = T.rotation() * Eigen::Vector3d(nc.x, nc.y, nc.z);
        EXPECT_GT(nw.dot(n), std::cos(0.2 * M_PI / 180.0));
      }
    EXPECT_GT(expected, kCamera.width * kCamera.height / 2);
    EXPECT_GE(hits, expected);
    EXPECT_LT(bad_normals, hits / 20);
  }
}

TEST(Raycast, BackFacesAndRangeAreRespected) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0, 0.0, 0.0);
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.4; }, {-0.6, -0.6, -0.6}, {0.6, 0.6, 0.6});
  // From inside the sphere every ray meets the surface from behind (- to +): no hits.
  const RaycastResult inside = raycast(grid, kCamera, datasets::look_at({0.05, 0.02, 0.0}, {1.0, 0.0, 0.0}));
  EXPECT_EQ(inside.hit_count, 0);
  // The surface lies beyond max_depth_m: no hits; within: hits.
  const SE3 T = datasets::look_at({2.0, 0.0, 0.0}, c);
  RaycastOptions opts;
  opts.max_depth_m = 1.5;
  EXPECT_EQ(raycast(grid, kCamera, T, opts).hit_count, 0);
  opts.max_depth_m = 1.7;
  EXPECT_GT(raycast(grid, kCamera, T, opts).hit_count, 1000);
  // Rays starting beyond the centre (the front surface is nearer than 1.92 m): they start inside the sphere or
  // behind it, see only - to + back faces and leave: nothing.
  opts.min_depth_m = 2.1;
  opts.max_depth_m = 5.0;
  EXPECT_EQ(raycast(grid, kCamera, T, opts).hit_count, 0);
}

// A small sphere just in front of the camera (its blocks straddle the near plane) before a wall 2.5 m away: the
// range image must neither cut the wall off nor let the near blocks hide it; rays beside the sphere cross the
// empty space between the two (skipped a block or a 4^3-block region at a time) and must still hit the wall.
TEST(Raycast, NearObjectBeforeFarWallAcrossTheNearPlane) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.02, 0.01, 0.45);
  const double r = 0.2;  // nearest surface point at 0.25 m; its blocks reach in front of min_depth_m = 0.2
  const Eigen::Vector3d n(0.0, 0.0, -1.0);
  const double offset = -2.5;  // the plane z = 2.5 facing the camera
  auto sphere = [&](const Eigen::Vector3d& p) { return (p - c).norm() - r; };
  auto plane = [&](const Eigen::Vector3d& p) { return n.dot(p) - offset; };
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return std::min(sphere(p), plane(p)); }, {-2.5, -2.0, 0.0},
       {2.5, 2.0, 2.7});
  const SE3 T;  // camera at the origin looking along +z
  const RaycastResult out = raycast(grid, kCamera, T);
  const DepthImage ds = testing::render_sphere_depth(kCamera, T, c, r);
  const DepthImage dp = testing::render_plane_depth(kCamera, T, n, offset);
  int sphere_hits = 0, wall_hits = 0;
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      const float truth = ds(x, y) > 0.0f ? ds(x, y) : dp(x, y);
      ASSERT_GT(truth, 0.0f);
      // Silhouette pixels of the sphere see a grazing surface: compare only clear cases.
      auto on_sphere = [&](int u, int v) {
        return ds(std::clamp(u, 0, kCamera.width - 1), std::clamp(v, 0, kCamera.height - 1)) > 0.0f;
      };
      const bool here = on_sphere(x, y);
      const bool near_rim = on_sphere(x + 1, y) != here || on_sphere(x - 1, y) != here ||
                            on_sphere(x, y + 1) != here || on_sphere(x, y - 1) != here;
      if (near_rim) continue;
      ASSERT_GT(out.depth(x, y), 0.0f) << x << "," << y;
      EXPECT_NEAR(out.depth(x, y), truth, 0.3 * 0.01) << x << "," << y;
      (ds(x, y) > 0.0f ? sphere_hits : wall_hits) += 1;
    }
  EXPECT_GT(sphere_hits, kCamera.width * kCamera.height / 4);
  EXPECT_GT(wall_hits, kCamera.width * kCamera.height / 8);
}

// Pixels are independent: one thread or many give bit-identical images.
TEST(Raycast, DeterministicAcrossThreadCounts) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.4; }, c.array() - 0.5, c.array() + 0.5);
  const SE3 T = datasets::look_at({1.1, 0.3, -0.6}, c);
  const RaycastResult many = raycast(grid, kCamera, T);
  RaycastResult one;
  {
    tbb::global_control limit(tbb::global_control::max_allowed_parallelism, 1);
    one = raycast(grid, kCamera, T);
  }
  ASSERT_GT(many.hit_count, 1000);
  EXPECT_EQ(one.hit_count, many.hit_count);
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      EXPECT_EQ(one.depth(x, y), many.depth(x, y));
      EXPECT_EQ(one.normals(x, y).x, many.normals(x, y).x);
      EXPECT_EQ(one.normals(x, y).y, many.normals(x, y).y);
      EXPECT_EQ(one.normals(x, y).z, many.normals(x, y).z);
      EXPECT_EQ(one.color(x, y), many.color(x, y));
    }
}

TEST(Raycast, EmptyGridAndBadInput) {
  VoxelBlockGrid grid(raycast_params_1cm());
  RaycastResult out = raycast(grid, kCamera, SE3());
  EXPECT_EQ(out.hit_count, 0);
  for (const auto& v : out.vertices.pixels()) EXPECT_EQ(v.w, 0.0f);
  for (float d : out.depth.pixels()) EXPECT_EQ(d, 0.0f);
  RaycastOptions bad;
  bad.step_fraction = 1.5;
  EXPECT_THROW(raycast(grid, kCamera, SE3(), bad), Error);
  bad = RaycastOptions{};
  bad.min_depth_m = 2.0;
  bad.max_depth_m = 1.0;
  EXPECT_THROW(raycast(grid, kCamera, SE3(), bad), Error);
  PinholeCamera cam = kCamera;
  cam.fx = 0.0;
  EXPECT_THROW(raycast(grid, cam, SE3()), Error);
  // Buffers are reused when the size stays.
  const hf_float4* before = out.vertices.data();
  raycast(grid, kCamera, SE3(), RaycastOptions{}, &out);
  EXPECT_EQ(out.vertices.data(), before);
}

// How a raycast with RaycastOptions::depth_hint compares with the full march from the same pose. A pixel agrees
// when both miss, or both hit with depths within kDepthTol_m and equally valid normals within kNormalTol_deg.
// With the crossing refined to 0.001 voxel the two marches, which sample the same bracket at different points,
// agree far more closely than that wherever they find the same crossing.
constexpr double kDepthTol_m = 0.01 * 0.01;  // 0.01 voxel
constexpr double kNormalTol_deg = 0.5;

struct HintComparison {
  int hits_plain = 0, hits_hint = 0;
  std::vector<std::pair<int, int>> differ;  // pixels that do not agree
};

HintComparison compare_hint(const RaycastResult& plain, const RaycastResult& hinted) {
  HintComparison c;
  c.hits_plain = plain.hit_count;
  c.hits_hint = hinted.hit_count;
  for (int y = 0; y < plain.depth.height(); ++y)
    for (int x = 0; x < plain.depth.width(); ++x) {
      const float a = plain.depth(x, y), b = hinted.depth(x, y);
      if (a == 0.0f && b == 0.0f) continue;
      bool agree = a > 0.0f && b > 0.0f && std::abs(double(a) - double(b)) <= kDepthTol_m;
      const hf_float4 na = plain.normals(x, y), nb = hinted.normals(x, y);
      agree = agree && na.w == nb.w;
      if (agree && na.w != 0.0f) {
        const double dot = double(na.x) * nb.x + double(na.y) * nb.y + double(na.z) * nb.z;
        agree = std::acos(std::clamp(dot, -1.0, 1.0)) * 180.0 / M_PI <= kNormalTol_deg;
      }
      if (!agree) c.differ.emplace_back(x, y);
    }
  return c;
}

// VolumeSampler's fast paths (one look-up per distinct block, missing blocks read as unobserved voxels, the cached
// cell, the branch-free 32-voxel normal gather) return exactly what the general paths (every voxel through
// voxel(), early exits) return: the same validity and bit-identical values, on a fused noisy room, at points
// chosen to straddle block borders (into missing blocks too), in sequences that hit the cell cache, and with a
// minimum weight that makes part of the voxels unobserved.
TEST(RaycastSampler, FastPathsMatchTheGeneralPathsBitForBit) {
  VoxelBlockGrid grid(raycast_params_1cm());
  fuse_noisy_room(grid, 12, 3);
  const auto blocks = grid.blocks();
  ASSERT_GT(blocks.size(), 100u);
  // The fast paths read the grid itself, the general ones a BlockLookup over the same blocks: the two ways of
  // finding a block agree too.
  const BlockLookup lookup(grid.blocks_unordered());
  for (const float min_weight : {0.0f, 2.5f}) {
    VolumeSampler fast(grid, min_weight), general(lookup, min_weight);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> any(-1.5f, 8.5f), border(6.5f, 8.5f), tiny(-0.02f, 0.02f);
    int sdf_valid = 0, normal_valid = 0, crossing = 0, unobserved = 0;
    for (int n = 0; n < 20000; ++n) {
      const BlockCoord b = blocks[rng() % blocks.size()].first;
      Eigen::Vector3f p(8.0f * float(b.x), 8.0f * float(b.y), 8.0f * float(b.z));
      for (int a = 0; a < 3; ++a) p[a] += (rng() & 1) ? border(rng) : any(rng);
      // A few samples close together (the cell cache), then the normal there.
      for (int r = 0; r < 3; ++r) {
        const Eigen::Vector3f q = p + Eigen::Vector3f(tiny(rng), tiny(rng), tiny(rng));
        float s_fast = 0.0f, s_general = 0.0f;
        const bool ok = fast.sdf(q, &s_fast);
        ASSERT_EQ(ok, general.sdf_reference(q, &s_general)) << q.transpose();
        if (ok) {
          ASSERT_EQ(s_fast, s_general) << q.transpose();
        }
        sdf_valid += ok ? 1 : 0;
        unobserved += ok ? 0 : 1;
        crossing += (std::floor(q.x()) - 8.0f * float(b.x) >= 7.0f || std::floor(q.y()) - 8.0f * float(b.y) >= 7.0f ||
                     std::floor(q.z()) - 8.0f * float(b.z) >= 7.0f) ? 1 : 0;
      }
      float s_color = 0.0f, s_general = 0.0f;
      Eigen::Vector3f rgb;
      const bool ok_color = fast.sdf_color(p, &s_color, &rgb);
      ASSERT_EQ(ok_color, general.sdf_reference(p, &s_general));
      if (ok_color) {
        EXPECT_EQ(s_color, s_general);
        for (int c = 0; c < 3; ++c) EXPECT_TRUE(rgb[c] >= 0.0f && rgb[c] <= 255.0f);
      }
      Eigen::Vector3f n_fast, n_general;
      const bool ok_n = fast.normal(p, &n_fast);
      ASSERT_EQ(ok_n, general.normal_reference(p, &n_general)) << p.transpose();
      if (ok_n) {
        ASSERT_EQ(n_fast.x(), n_general.x());
        ASSERT_EQ(n_fast.y(), n_general.y());
        ASSERT_EQ(n_fast.z(), n_general.z());
        ++normal_valid;
      }
    }
    // Not vacuous: valid and invalid samples, cells across block borders, valid normals.
    EXPECT_GT(sdf_valid, 3000) << "min_weight " << min_weight;
    EXPECT_GT(unobserved, 3000) << "min_weight " << min_weight;
    EXPECT_GT(crossing, 20000) << "min_weight " << min_weight;
    EXPECT_GT(normal_valid, 500) << "min_weight " << min_weight;
  }
}

// The SLAM pipeline's case on the sphere: fuse noise-free depth from a ring of poses, then raycast at the pose of
// the frame just integrated with and without that frame's depth as the hint. They agree everywhere except at a
// few silhouette pixels (grazing rays, where the fused field has more than one crossing within the bracket and
// the marches meet different crossings or one of them an unobserved sample); measured: 20 of 7 832 hits, all
// within 4 pixels of the silhouette.
TEST(Raycast, DepthHintOnTheSphereMatchesTheFullMarch) {
  const PinholeCamera camera = kCamera;
  const Eigen::Vector3d c = datasets::kSphereCentre;
  const double r = datasets::kSphereRadius_m;
  VoxelBlockGrid grid(raycast_params_1cm());
  const std::vector<SE3> poses = datasets::ring_poses(c, 1.4, 8);
  DepthImage last;
  for (const SE3& T : poses) {
    last = testing::render_sphere_depth(camera, T, c, r);
    integrate(grid, last, ColorImage(), camera, T);
  }
  RaycastOptions opts;
  opts.shade = false;
  const RaycastResult plain = raycast(grid, camera, poses.back(), opts);
  opts.depth_hint = &last;
  const RaycastResult hinted = raycast(grid, camera, poses.back(), opts);
  const HintComparison cmp = compare_hint(plain, hinted);
  ASSERT_GT(cmp.hits_plain, 3000);
  EXPECT_LE(cmp.differ.size(), size_t(cmp.hits_plain / 250));
  for (const auto& [x, y] : cmp.differ) {
    bool silhouette = false;  // a pixel within 4 of it sees no sphere
    for (int v = std::max(0, y - 4); v <= std::min(camera.height - 1, y + 4); ++v)
      for (int u = std::max(0, x - 4); u <= std::min(camera.width - 1, x + 4); ++u) silhouette |= last(u, v) == 0.0f;
    EXPECT_TRUE(silhouette) << x << "," << y << ": plain " << plain.depth(x, y) << " m, hinted " << hinted.depth(x, y);
  }
}

// The same on the room preset with Kinect-like noise (depth edges, grazing walls, ten fused noisy frames): the
// pixels that differ are a small fraction (measured: 92 of 19 200 = 0.48 %, at depth edges and on noisy far
// surfaces (3-4 m, sigma_z 2-3 cm) where the field has several crossings and the hinted search takes the one
// nearest the measured depth, the full march the first: against the noise-free depth, RMS 2.8 cm for the hinted
// crossing and 28 cm for the full march's). Every pixel the full march hits is hit by the hinted one too; the
// hinted one hits 53 more (RMS 0.8 cm from the truth), at the fringe of the observed volume (the image border,
// depth edges) where the full march met unobserved samples just before the surface.
TEST(Raycast, DepthHintOnTheNoisyRoomMatchesTheFullMarch) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const datasets::SyntheticFrame f = fuse_noisy_room(grid, 40, 4);
  RaycastOptions opts;
  opts.shade = false;
  const RaycastResult plain = raycast(grid, kCamera, f.T_world_camera, opts);
  opts.depth_hint = &f.depth;
  const RaycastResult hinted = raycast(grid, kCamera, f.T_world_camera, opts);
  const HintComparison cmp = compare_hint(plain, hinted);
  const int n = kCamera.width * kCamera.height;
  ASSERT_GT(cmp.hits_plain, n * 9 / 10);
  EXPECT_LE(cmp.differ.size(), size_t(n / 200));
  int only_hinted = 0;
  double e2_plain = 0.0, e2_hinted = 0.0, e2_only = 0.0;
  int both = 0;
  for (const auto& [x, y] : cmp.differ) {
    EXPECT_GT(hinted.depth(x, y), 0.0f) << x << "," << y << ": only the full march hits";
    const double truth = f.depth_clean(x, y);
    if (plain.depth(x, y) == 0.0f) {
      ++only_hinted;
      e2_only += std::pow(hinted.depth(x, y) - truth, 2);
    } else if (hinted.depth(x, y) > 0.0f) {
      ++both;
      e2_plain += std::pow(plain.depth(x, y) - truth, 2);
      e2_hinted += std::pow(hinted.depth(x, y) - truth, 2);
    }
  }
  EXPECT_EQ(cmp.hits_hint - cmp.hits_plain, only_hinted);
  EXPECT_LE(only_hinted, n / 250);
  // Against the noise-free depth: the hits only the hinted search finds are no worse than one raw measurement at
  // the room's far wall (4 m), and where both hit different crossings the hinted one is the nearer to the truth.
  const double sigma_far = hf_kinect_axial_sigma_m(4.0f);
  ASSERT_GT(only_hinted, 0);
  ASSERT_GT(both, 0);
  EXPECT_LE(std::sqrt(e2_only / only_hinted), sigma_far);
  EXPECT_LT(std::sqrt(e2_hinted / both), std::sqrt(e2_plain / both));
  EXPECT_LE(std::sqrt(e2_hinted / both), 2.0 * sigma_far);
}

// A hint of zeros (no pixel hinted; negative, NaN and infinite values count as zero) is exactly no hint; a hint
// of the wrong size is rejected.
TEST(Raycast, DepthHintOfZerosIsNoHintAndWrongSizeThrows) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.4; }, c.array() - 0.5, c.array() + 0.5);
  const SE3 T = datasets::look_at({1.1, 0.3, -0.6}, c);
  const RaycastResult plain = raycast(grid, kCamera, T);
  DepthImage zeros(kCamera.width, kCamera.height, 0.0f);
  const float kNone[4] = {0.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(),
                          std::numeric_limits<float>::infinity()};
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) zeros(x, y) = kNone[(x + y) % 4];
  RaycastOptions opts;
  opts.depth_hint = &zeros;
  const RaycastResult hinted = raycast(grid, kCamera, T, opts);
  ASSERT_GT(plain.hit_count, 1000);
  EXPECT_EQ(hinted.hit_count, plain.hit_count);
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      ASSERT_EQ(hinted.depth(x, y), plain.depth(x, y)) << x << "," << y;
      EXPECT_EQ(hinted.normals(x, y).x, plain.normals(x, y).x);
      EXPECT_EQ(hinted.normals(x, y).y, plain.normals(x, y).y);
      EXPECT_EQ(hinted.normals(x, y).z, plain.normals(x, y).z);
      EXPECT_EQ(hinted.normals(x, y).w, plain.normals(x, y).w);
      EXPECT_EQ(hinted.color(x, y), plain.color(x, y));
      EXPECT_EQ(hinted.shaded(x, y), plain.shaded(x, y));
    }
  const DepthImage wrong(kCamera.width / 2, kCamera.height, 1.0f);
  opts.depth_hint = &wrong;
  EXPECT_THROW(opts.validate(kCamera), Error);
  EXPECT_NO_THROW(opts.validate());  // the size is only known with the camera
  EXPECT_THROW(raycast(grid, kCamera, T, opts), Error);
  opts.depth_hint = &zeros;
  EXPECT_NO_THROW(opts.validate(kCamera));
}

// color = false (the SLAM pipeline's tracking raycast) leaves the colour image black and changes nothing else.
TEST(Raycast, WithoutColourTheGeometryIsUnchanged) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.4; }, c.array() - 0.5, c.array() + 0.5);
  const SE3 T = datasets::look_at({1.1, 0.3, -0.6}, c);
  const RaycastResult with = raycast(grid, kCamera, T);
  RaycastOptions opts;
  opts.color = false;
  const RaycastResult without = raycast(grid, kCamera, T, opts);
  ASSERT_GT(with.hit_count, 1000);
  EXPECT_EQ(without.hit_count, with.hit_count);
  int coloured = 0;
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      ASSERT_EQ(without.depth(x, y), with.depth(x, y)) << x << "," << y;
      EXPECT_EQ(without.normals(x, y).x, with.normals(x, y).x);
      EXPECT_EQ(without.normals(x, y).w, with.normals(x, y).w);
      EXPECT_EQ(without.shaded(x, y), with.shaded(x, y));
      EXPECT_EQ(without.color(x, y), Rgb8{});
      coloured += with.color(x, y) != Rgb8{} ? 1 : 0;
    }
  EXPECT_GT(coloured, with.hit_count / 2);  // fill() paints the sphere, so the comparison is not vacuous
}

// The render for people in the fused colours (colored_shading, what `run` writes as render.png): a sphere fused
// from one view whose colour image is red on the left half and green on the right comes out red-dominant on the
// left and green-dominant on the right, each pixel its fused colour times the head-light shade (within the 8-bit
// rounding of both); the same sphere fused without colour keeps the grey shading pixel for pixel.
TEST(Raycast, ColoredShadingShowsTheFusedColour) {
  const Eigen::Vector3d c(0.02, -0.01, 1.0);
  const SE3 T = datasets::look_at({0.0, 0.0, 0.0}, c);
  const DepthImage depth = testing::render_sphere_depth(kCamera, T, c, 0.3);
  ColorImage colour(kCamera.width, kCamera.height);
  const Rgb8 red{200, 40, 30}, green{30, 180, 50};
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) colour(x, y) = x < kCamera.width / 2 ? red : green;
  VoxelBlockGrid grid(raycast_params_1cm()), grey_grid(raycast_params_1cm());
  integrate(grid, depth, colour, kCamera, T);
  integrate(grey_grid, depth, ColorImage(), kCamera, T);
  const RaycastResult r = raycast(grid, kCamera, T);
  const ColorImage shown = colored_shading(r);
  ASSERT_GT(r.hit_count, 3000);
  int left = 0, right = 0;
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      const Rgb8 s = shown(x, y), g = r.shaded(x, y), f = r.color(x, y);
      if (r.depth(x, y) <= 0.0f) {
        EXPECT_EQ(s, Rgb8{}) << x << "," << y;
        continue;
      }
      if (f == Rgb8{}) {  // no colour fused at the edge of the observed band: the grey shading
        EXPECT_EQ(s, g) << x << "," << y;
        continue;
      }
      // colour x shade / 255, rounded once from the 8-bit grey: within one level of the exact product.
      EXPECT_NEAR(s.r, f.r * g.r / 255.0, 1.0) << x << "," << y;
      EXPECT_NEAR(s.g, f.g * g.r / 255.0, 1.0) << x << "," << y;
      // Away from the seam (a voxel's trilinear reach, 3 pixels at 1 m) each side shows its colour.
      if (std::abs(x - kCamera.width / 2) < 4 || g.r < 100) continue;
      if (x < kCamera.width / 2) {
        ++left;
        EXPECT_GT(s.r, 2 * s.g) << x << "," << y;
        EXPECT_GT(s.r, 2 * s.b) << x << "," << y;
      } else {
        ++right;
        EXPECT_GT(s.g, 2 * s.r) << x << "," << y;
        EXPECT_GT(s.g, 2 * s.b) << x << "," << y;
      }
    }
  EXPECT_GT(left, 1000);
  EXPECT_GT(right, 1000);
  const RaycastResult grey = raycast(grey_grid, kCamera, T);
  EXPECT_EQ(colored_shading(grey).pixels(), grey.shaded.pixels());
  RaycastOptions no_shade;
  no_shade.shade = false;
  EXPECT_THROW(colored_shading(raycast(grid, kCamera, T, no_shade)), Error);
}

// blocks_in_view holds every block a raycast can read: at points on rays through pixels across the image (its
// border rows and columns included) at depths from min_depth_m to max_depth_m, every existing block holding a voxel
// of the 4 x 4 x 4 neighbourhood a sample and its normal read is in the set. Seen from inside the room with a
// 2.5 m range the set is a fraction of the map (measured: 1 208-1 269 of 3 537 blocks), and without the reach
// margin (the bounding spheres alone) this test fails.
TEST(Raycast, BlocksInViewHoldEveryBlockARayReads) {
  VoxelBlockGrid grid(raycast_params_1cm());
  fuse_noisy_room(grid, 40, 4);
  datasets::SyntheticOptions o;
  o.preset = "room";
  o.frames = 40;
  o.camera = kCamera;
  const datasets::SyntheticSequence seq(o);
  RaycastOptions opts;
  opts.min_depth_m = 0.3;
  opts.max_depth_m = 2.5;
  const double voxel_m = grid.params().voxel_m;
  std::mt19937 rng(11);
  for (const int i : {2, 17, 33}) {
    const SE3 T = seq.frame(i).T_world_camera;
    const auto in_view = blocks_in_view(grid, kCamera, T, opts);
    std::set<std::tuple<int, int, int>> set;
    for (const auto& [c, b] : in_view) set.emplace(c.x, c.y, c.z);
    EXPECT_LT(set.size(), grid.block_count() / 2) << "pose " << i;
    std::uniform_real_distribution<double> u(0.0, kCamera.width - 1.0), v(0.0, kCamera.height - 1.0);
    std::uniform_real_distribution<double> z(opts.min_depth_m, opts.max_depth_m);
    int read = 0;
    for (int n = 0; n < 20000; ++n) {
      double x = u(rng), y = v(rng), d = z(rng);
      if (n % 4 == 1) x = (n / 4) % 2 == 0 ? 0.0 : kCamera.width - 1.0;  // the border columns and rows
      if (n % 4 == 2) y = (n / 4) % 2 == 0 ? 0.0 : kCamera.height - 1.0;
      if (n % 8 == 3) d = (n / 8) % 2 == 0 ? opts.min_depth_m : opts.max_depth_m;
      const Eigen::Vector3d p_cam((x - kCamera.cx) / kCamera.fx * d, (y - kCamera.cy) / kCamera.fy * d, d);
      const Eigen::Vector3d p_vox = grid.voxel_coords(T * p_cam);
      const int i0 = int(std::floor(p_vox.x())), j0 = int(std::floor(p_vox.y())), k0 = int(std::floor(p_vox.z()));
      for (int dk = -1; dk <= 2; ++dk)
        for (int dj = -1; dj <= 2; ++dj)
          for (int di = -1; di <= 2; ++di) {
            const Eigen::Vector3d voxel(i0 + di, j0 + dj, k0 + dk);
            const BlockCoord c = grid.block_of((voxel + Eigen::Vector3d::Constant(0.5)) * voxel_m);
            if (grid.find(c) == nullptr) continue;
            ++read;
            ASSERT_TRUE(set.count({c.x, c.y, c.z})) << "pose " << i << ": block " << c.x << " " << c.y << " " << c.z
                                                    << " read at pixel (" << x << ", " << y << "), depth " << d;
          }
    }
    EXPECT_GT(read, 10000) << "pose " << i;
  }
}

// Skipping blocks without surface (RaycastOptions::skip_blocks, VoxelBlockGrid::surface_free) changes where the
// march samples, not what it finds, except at a few pixels where two sampling patterns of the same field differ
// anyway. On the noise-free sphere every pixel agrees to 0.01 voxel but for silhouette pixels (measured: 2 of
// 3 873 hits; grazing rays). On the noisy room: at depth edges and the image border, where unobserved samples sit
// just in front of the surface, and on noisy far surfaces with several crossings (measured: 62 of 19 200 pixels,
// 18 552 against 18 546 hits); against the noise-free depth the pixels both hit are equally accurate (RMS 6.86
// against 6.75 cm, the far walls' noise and multiple crossings).
TEST(Raycast, SkippingBlocksWithoutSurfaceKeepsTheHits) {
  {
    const Eigen::Vector3d c = datasets::kSphereCentre;
    VoxelBlockGrid grid(raycast_params_1cm());
    const std::vector<SE3> poses = datasets::ring_poses(c, 1.4, 8);
    for (const SE3& T : poses)
      integrate(grid, testing::render_sphere_depth(kCamera, T, c, datasets::kSphereRadius_m), ColorImage(), kCamera,
                T);
    size_t skippable = 0;
    for (const auto& [coord, block] : grid.blocks()) skippable += grid.surface_free(coord) ? 1 : 0;
    EXPECT_GT(skippable, grid.block_count() / 10);  // not vacuous (measured: 196 of 932)
    RaycastOptions opts;
    opts.shade = false;
    opts.skip_blocks = false;
    const SE3 T = datasets::look_at(c + Eigen::Vector3d(0.9, 0.5, -0.9), c);
    const RaycastResult walked = raycast(grid, kCamera, T, opts);
    opts.skip_blocks = true;
    const RaycastResult skipped = raycast(grid, kCamera, T, opts);
    const HintComparison cmp = compare_hint(walked, skipped);
    ASSERT_GT(cmp.hits_plain, 3000);
    EXPECT_LE(std::abs(cmp.hits_hint - cmp.hits_plain), 2);
    EXPECT_LE(cmp.differ.size(), size_t(cmp.hits_plain / 1000));
    const DepthImage truth = testing::render_sphere_depth(kCamera, T, c, datasets::kSphereRadius_m);
    for (const auto& [x, y] : cmp.differ) {
      bool silhouette = false;  // a pixel within 4 of it sees no sphere
      for (int v = std::max(0, y - 4); v <= std::min(kCamera.height - 1, y + 4); ++v)
        for (int u = std::max(0, x - 4); u <= std::min(kCamera.width - 1, x + 4); ++u)
          silhouette |= truth(u, v) == 0.0f;
      EXPECT_TRUE(silhouette) << x << "," << y << ": walked " << walked.depth(x, y) << " m, skipped "
                              << skipped.depth(x, y);
    }
  }
  VoxelBlockGrid grid(raycast_params_1cm());
  const datasets::SyntheticFrame f = fuse_noisy_room(grid, 40, 4);
  RaycastOptions opts;
  opts.shade = false;
  opts.skip_blocks = false;
  const RaycastResult walked = raycast(grid, kCamera, f.T_world_camera, opts);
  opts.skip_blocks = true;
  const RaycastResult skipped = raycast(grid, kCamera, f.T_world_camera, opts);
  const HintComparison cmp = compare_hint(walked, skipped);
  const int n = kCamera.width * kCamera.height;
  ASSERT_GT(cmp.hits_plain, n * 9 / 10);
  EXPECT_LE(cmp.differ.size(), size_t(n / 200));
  EXPECT_NEAR(cmp.hits_hint, cmp.hits_plain, n / 500);
  double e2_walked = 0.0, e2_skipped = 0.0;
  int both = 0;
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      const double truth = f.depth_clean(x, y), a = walked.depth(x, y), b = skipped.depth(x, y);
      if (truth <= 0.0 || a <= 0.0 || b <= 0.0) continue;
      ++both;
      e2_walked += (a - truth) * (a - truth);
      e2_skipped += (b - truth) * (b - truth);
    }
  ASSERT_GT(both, n * 9 / 10);
  EXPECT_NEAR(std::sqrt(e2_skipped / both), std::sqrt(e2_walked / both), 0.1 * std::sqrt(e2_walked / both));
}

// forward_project_depth: with the identity every vertex lands on its own pixel; of two on one pixel the nearer
// stays; invalid vertices, points behind the camera and outside the image leave 0; a non-finite pose throws.
TEST(ForwardProjectDepth, ZBufferOfTheMovedVertices) {
  const PinholeCamera cam = kCamera;
  VertexMap v(cam.width, cam.height, hf_invalid4());
  auto put = [&](int x, int y, double z) {
    const Eigen::Vector3d p = cam.backproject(x, y, z);
    v(x, y) = hf_make_float4(float(p.x()), float(p.y()), float(p.z()), 1.0f);
  };
  put(60, 50, 1.5);
  put(50, 60, 2.0);
  put(51, 60, 1.0);
  DepthImage out;
  forward_project_depth(v, SE3(), cam, &out);
  ASSERT_EQ(out.width(), cam.width);
  ASSERT_EQ(out.height(), cam.height);
  int nonzero = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) nonzero += out(x, y) != 0.0f ? 1 : 0;
  EXPECT_EQ(nonzero, 3);
  EXPECT_FLOAT_EQ(out(60, 50), 1.5f);
  EXPECT_FLOAT_EQ(out(51, 60), 1.0f);
  // Two vertices on one pixel's ray, the nearer one arriving second (the loop runs along rows) or first.
  auto put_on_ray = [&](int x, int y, int ray_x, double z) {
    const Eigen::Vector3d q = cam.backproject(ray_x, y, z);
    v(x, y) = hf_make_float4(float(q.x()), float(q.y()), float(q.z()), 1.0f);
  };
  put_on_ray(49, 60, 50, 3.0);  // lands on (50, 60) before (50, 60)'s own vertex at 2 m
  put_on_ray(20, 30, 21, 1.0);
  put(21, 30, 2.5);
  forward_project_depth(v, SE3(), cam, &out);
  EXPECT_FLOAT_EQ(out(50, 60), 2.0f);
  EXPECT_FLOAT_EQ(out(21, 30), 1.0f);
  EXPECT_EQ(out(49, 60), 0.0f);
  EXPECT_EQ(out(20, 30), 0.0f);
  // Moving the camera 0.75 m forward along its axis puts every point 0.75 m nearer (the one at 1.5 m to 0.75 m,
  // where it projects, twice as far from the principal point); the points at 1 m or nearer would be within 0.25 m
  // and land elsewhere; moving 3 m forward puts every point behind the camera.
  forward_project_depth(v, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, -0.75)), cam, &out);
  const Eigen::Vector2d uv = cam.project(cam.backproject(60, 50, 1.5) - Eigen::Vector3d(0.0, 0.0, 0.75));
  ASSERT_TRUE(uv.x() > 0.0 && uv.y() > 0.0) << uv.transpose();
  EXPECT_FLOAT_EQ(out(int(std::floor(uv.x() + 0.5)), int(std::floor(uv.y() + 0.5))), 0.75f);
  forward_project_depth(v, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.0, 0.0, -3.0)), cam, &out);
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) ASSERT_EQ(out(x, y), 0.0f) << x << "," << y;
  const SE3 bad(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0.0, 0.0));
  EXPECT_THROW(forward_project_depth(v, bad, cam, &out), Error);
}

// On a sphere, the raycast at one pose moved to a pose 3 cm and 3 degrees away predicts the raycast there. Where
// both have depth they differ by what the position within a pixel changes on the surface: the forward projection
// keeps the point nearest to the pixel centre, not the one on its ray, so the error is up to half a pixel's
// footprint p = z / f (at most 11 mm here: z <= 1.45 m, f = 131 px) times the slope tan(theta) of the depth. The
// visible part of a sphere with incidence below theta covers sin^2(theta) of its image: half of it has
// tan(theta) < 1, where an offset uniform within the pixel averages p / 4 along the slope; nine tenths has
// tan(theta) < 3. And the moved points cover nearly all of the new view's surface (the motion changes the scale
// by under 3 %, so few pixels receive no point).
TEST(ForwardProjectDepth, PredictsTheRaycastAtANearbyPose) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  const double r = 0.4;
  fill_raycast_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - r; }, c.array() - 0.5, c.array() + 0.5);
  const SE3 A = datasets::look_at({1.3, -0.4, 0.5}, c);
  const SE3 B = A * SE3(Eigen::Quaterniond(Eigen::AngleAxisd(3.0 * M_PI / 180.0, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())),
                        Eigen::Vector3d(0.02, -0.01, 0.02));
  RaycastOptions opts;
  opts.shade = false;
  const RaycastResult at_a = raycast(grid, kCamera, A, opts), at_b = raycast(grid, kCamera, B, opts);
  DepthImage predicted;
  forward_project_depth(at_a.vertices, B.inverse() * A, kCamera, &predicted);
  std::vector<double> err;
  int uncovered = 0;
  for (int y = 0; y < kCamera.height; ++y)
    for (int x = 0; x < kCamera.width; ++x) {
      if (at_b.depth(x, y) == 0.0f) continue;
      if (predicted(x, y) == 0.0f) {
        ++uncovered;
        continue;
      }
      err.push_back(std::abs(double(predicted(x, y)) - double(at_b.depth(x, y))));
    }
  ASSERT_GT(err.size(), size_t(3000));
  std::sort(err.begin(), err.end());
  const double footprint = 1.45 / kCamera.fx;
  EXPECT_LT(err[err.size() / 2], footprint / 4.0);
  EXPECT_LT(err[err.size() * 9 / 10], footprint / 2.0 * 3.0);
  EXPECT_LT(uncovered, int(err.size()) / 20);
}

// The sampled tracking raycast (fusion/raycast_sampled.h) equals the full one at every cast pixel, bit for bit, with
// and without a depth hint, and reads as a miss elsewhere; the mask grows by a square window.
TEST(RaycastSampled, EqualsTheFullRaycastAtTheCastPixels) {
  VoxelBlockGrid grid(raycast_params_1cm());
  const datasets::SyntheticFrame f = fuse_noisy_room(grid, 9, 4);
  Image<std::uint8_t> rays(kCamera.width, kCamera.height, 0);
  std::mt19937 rng(7);
  for (std::uint8_t& b : rays.pixels()) b = rng() % 5 == 0 ? 1 : 0;
  for (const DepthImage* hint : {static_cast<const DepthImage*>(nullptr), &f.depth}) {
    RaycastOptions opts;
    opts.depth_hint = hint;
    const RaycastResult full = raycast(grid, kCamera, f.T_world_camera, opts);
    RaycastResult sampled;
    raycast_sampled(grid, kCamera, f.T_world_camera, opts, rays, &sampled);
    int hits = 0, cast = 0;
    for (int y = 0; y < kCamera.height; ++y)
      for (int x = 0; x < kCamera.width; ++x) {
        if (rays(x, y) == 0) {
          EXPECT_EQ(sampled.depth(x, y), 0.0f);
          EXPECT_EQ(sampled.vertices(x, y).w, 0.0f);
          EXPECT_EQ(sampled.normals(x, y).w, 0.0f);
          continue;
        }
        ++cast;
        hits += full.depth(x, y) > 0.0f;
        ASSERT_EQ(std::memcmp(&sampled.depth(x, y), &full.depth(x, y), sizeof(float)), 0) << x << "," << y;
        ASSERT_EQ(std::memcmp(&sampled.vertices(x, y), &full.vertices(x, y), sizeof(hf_float4)), 0);
        ASSERT_EQ(std::memcmp(&sampled.normals(x, y), &full.normals(x, y), sizeof(hf_float4)), 0);
        EXPECT_EQ(sampled.color(x, y), full.color(x, y));
        EXPECT_EQ(sampled.shaded(x, y), full.shaded(x, y));
      }
    EXPECT_GT(hits, cast / 2);
    EXPECT_EQ(sampled.hit_count, hits);
  }
  RaycastResult out;
  EXPECT_THROW(raycast_sampled(grid, kCamera, f.T_world_camera, {}, Image<std::uint8_t>(4, 4, 1), &out), Error);

  Image<std::uint8_t> one(9, 7, 0);
  one(0, 3) = 1, one(6, 6) = 1;
  const Image<std::uint8_t> grown = dilate_rays(one, 2);
  for (int y = 0; y < 7; ++y)
    for (int x = 0; x < 9; ++x) {
      const bool near = (x <= 2 && std::abs(y - 3) <= 2) || (x >= 4 && y >= 4);
      EXPECT_EQ(grown(x, y), near ? 1 : 0) << x << "," << y;
    }
  EXPECT_EQ(dilate_rays(one, 0).pixels(), one.pixels());
  EXPECT_THROW(dilate_rays(one, -1), Error);
}

}  // namespace
}  // namespace hf::fusion
