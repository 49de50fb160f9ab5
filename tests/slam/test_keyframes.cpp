// Keyframes (selection, compressed images, memory budget), loop candidates and the keyframe graph's edges, and the
// re-fusion queue of slam/reintegration.h.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.h"
#include "fusion/integrate.h"
#include "slam/keyframes.h"
#include "slam/loop_closure.h"
#include "slam/reintegration.h"

namespace hf::slam {
namespace {

SE3 keyframes_pose(double x_m, double yaw_deg = 0.0) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_deg * M_PI / 180.0, Eigen::Vector3d::UnitY())),
             Eigen::Vector3d(x_m, 0.0, 0.0));
}

DepthImage noisy_depth(int w, int h, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> d(0.5f, 4.0f);
  DepthImage img(w, h);
  for (float& v : img.pixels()) v = d(rng);
  img(0, 0) = 0.0f;                        // no depth stays no depth
  img(1, 0) = std::nanf("");               // NaN is no depth
  img(2, 0) = 20.0f;                       // beyond 13.1 m (the 16-bit range) is no depth
  return img;
}

TEST(CompressedRgbd, DepthRoundTripsToTheTumUnitAndColourIsKept) {
  const DepthImage depth = noisy_depth(64, 48, 1);
  ColorImage colour(64, 48, Rgb8{100, 150, 200});
  const CompressedRgbd c = CompressedRgbd::encode(depth, colour, 95);
  const DepthImage back = c.depth();
  ASSERT_EQ(back.width(), 64);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      const float d = depth(x, y);
      if (!(d > 0.0f) || !std::isfinite(d) || d > 13.0f) {
        EXPECT_EQ(back(x, y), 0.0f) << x << "," << y;
      } else {
        EXPECT_NEAR(back(x, y), d, 0.5f / 5000.0f + 1e-6f);  // half a 1/5000 m unit
      }
    }
  // Quantised depth is stored exactly.
  DepthImage q = depth;
  quantise_depth_tum(&q);
  EXPECT_EQ(CompressedRgbd::encode(q, {}, 90).depth().pixels(), q.pixels());
  const ColorImage cb = c.colour();
  ASSERT_EQ(cb.width(), 64);
  EXPECT_NEAR(cb(10, 10).r, 100, 3);  // JPEG of a flat colour
  EXPECT_NEAR(cb(10, 10).b, 200, 3);
  EXPECT_TRUE(CompressedRgbd::encode(depth, {}, 90).colour().empty());
  CompressedRgbd corrupt = c;
  corrupt.depth_png.resize(20);
  EXPECT_THROW(corrupt.depth(), Error);
}

TEST(KeyframeMap, SelectsByMotionAndFrameGap) {
  KeyframeOptions o;
  o.min_translation_m = 0.1;
  o.min_rotation_deg = 10.0;
  o.max_frames_between = 30;
  KeyframeMap map(o);
  const DepthImage d = noisy_depth(32, 24, 2);
  EXPECT_TRUE(map.wants_keyframe(keyframes_pose(0.0), 0));
  map.add(0, 0.0, keyframes_pose(0.0), Matrix6d::Identity(), d, {});
  EXPECT_FALSE(map.wants_keyframe(keyframes_pose(0.09), 5));
  EXPECT_TRUE(map.wants_keyframe(keyframes_pose(0.11), 5));
  EXPECT_FALSE(map.wants_keyframe(keyframes_pose(0.0, 9.0), 5));
  EXPECT_TRUE(map.wants_keyframe(keyframes_pose(0.0, 11.0), 5));
  EXPECT_TRUE(map.wants_keyframe(keyframes_pose(0.0), 30));
  map.add(30, 1.0, keyframes_pose(0.3), Matrix6d::Identity(), d, {});
  EXPECT_NEAR(map[1].path_m, 0.3, 1e-12);
  EXPECT_NEAR(map[1].T_previous_this.translation().x(), 0.3, 1e-12);
}

TEST(KeyframeMap, BudgetDropsTheOldestImagesNeverTheNewest) {
  KeyframeOptions o;
  KeyframeMap probe(o);
  const DepthImage d = noisy_depth(64, 48, 3);
  probe.add(0, 0.0, keyframes_pose(0.0), Matrix6d::Identity(), d, {});
  const double one_mb = double(probe.memory_bytes()) / (1024.0 * 1024.0);
  o.memory_budget_mb = 2.5 * one_mb;  // room for two keyframes' images
  KeyframeMap map(o);
  for (int i = 0; i < 5; ++i) map.add(size_t(i), i, keyframes_pose(0.2 * i), Matrix6d::Identity(), noisy_depth(64, 48, 3), {});
  EXPECT_FALSE(map.has_images(0));
  EXPECT_FALSE(map.has_images(2));
  EXPECT_TRUE(map.has_images(3));
  EXPECT_TRUE(map.has_images(4));
  EXPECT_TRUE(map.depth(0).empty());
  EXPECT_LE(double(map.memory_bytes()), o.memory_budget_mb * 1024.0 * 1024.0);
  o.memory_budget_mb = 0.0;  // even with no budget the newest keeps its images
  KeyframeMap none(o);
  none.add(0, 0.0, keyframes_pose(0.0), Matrix6d::Identity(), d, {});
  EXPECT_TRUE(none.has_images(0));
}

TEST(LoopCandidates, NeedGapPathAndProximity) {
  KeyframeMap map;
  const DepthImage d = noisy_depth(16, 12, 4);
  // A lap: out 1.5 m along x and back; keyframe 10 is back near keyframe 0.
  for (int i = 0; i <= 10; ++i) {
    const double x = i <= 5 ? 0.3 * i : 0.3 * (10 - i);
    map.add(size_t(i * 10), i, keyframes_pose(x), Matrix6d::Identity(), d, {});
  }
  ASSERT_NEAR(map[10].path_m, 3.0, 1e-9);
  LoopClosureOptions o;
  std::vector<AppearanceMatch> matches;
  for (size_t i : {9u, 0u, 1u, 5u, 8u}) matches.push_back({i, 0.0});
  const std::vector<size_t> c = loop_candidates(map, 10, matches, o);
  // 9 and 8: too recent; 5: 1.5 m away; 0 and 1 qualify, in appearance order.
  EXPECT_EQ(c, (std::vector<size_t>{0, 1}));
  o.min_path_m = 5.0;
  EXPECT_TRUE(loop_candidates(map, 10, matches, o).empty());
  EXPECT_TRUE(loop_candidates(map, 99, matches, o).empty());
}

TEST(KeyframeGraph, OdometryEdgesKeepTheTrackedMeasurementAndAreWellPosed) {
  KeyframeMap map;
  const DepthImage d = noisy_depth(16, 12, 5);
  map.add(0, 0.0, keyframes_pose(0.0), Matrix6d::Zero(), d, {});
  map.add(10, 1.0, keyframes_pose(0.2), 1e6 * Matrix6d::Identity(), d, {});
  map.set_pose(1, keyframes_pose(0.25));  // a later correction must not change the measurement
  const PoseGraph g = keyframe_graph(map, {{0, 1, keyframes_pose(0.2), 1e4 * Matrix6d::Identity()}});
  ASSERT_EQ(g.num_edges(), 2u);
  EXPECT_NEAR(g.edges()[0].T_from_to.translation().x(), 0.2, 1e-12);
  // Information per frame: 1e6 over 10 frames, plus the floor.
  EXPECT_NEAR(g.edges()[0].information(0, 0), 1e5 + 1.0, 1e-6);
  const Matrix6d floor_only = odometry_information(Matrix6d::Zero(), 0);
  EXPECT_GT(floor_only.ldlt().vectorD().minCoeff(), 0.0);
  Matrix6d nan = Matrix6d::Identity();
  nan(0, 0) = std::nan("");
  EXPECT_TRUE(odometry_information(nan, 3).allFinite());
}

// Keyframe window edges (loop_closure.window_keyframes) on a straight chain whose every registered step is biased:
// K keyframes truly d apart along x, each odometry edge measuring d + e, each window edge (i-2, i) measuring 2d
// exactly, every information lambda I (the chain's plus the floor 1). With rotations at identity the SE(3) log
// of a pure translation is the translation, so the graph is exactly the linear least squares
//   min sum (lambda + 1) (x_i - x_{i-1} - d - e)^2 + sum lambda (x_i - x_{i-2} - 2 d)^2,   x_0 = 0,
// which the test solves with Eigen. Far from the chain's ends a step s solves (lambda + 1)(s - d - e) + 2 lambda
// (2 s - 2 d) = 0: its error is e (lambda + 1) / (5 lambda + 1), a fifth of the chain's; the two end steps keep more.
TEST(KeyframeGraph, WindowEdgesCutABiasedChainsDriftToTheLeastSquaresSolution) {
  constexpr int K = 15;
  const double d = 0.1, e = 0.002, lambda = 1e4;
  KeyframeMap map;
  const DepthImage depth = noisy_depth(16, 12, 6);
  for (int i = 0; i < K; ++i) {
    map.add(size_t(i * 10), i, keyframes_pose((d + e) * i), lambda * Matrix6d::Identity(), depth, {});
    if (i > 0) map.set_odometry(size_t(i), keyframes_pose(d + e), lambda * Matrix6d::Identity());
  }
  std::vector<LoopEdge> window;
  for (int i = 2; i < K; ++i)
    window.push_back({size_t(i - 2), size_t(i), keyframes_pose(2 * d), lambda * Matrix6d::Identity()});
  const PoseGraph g = keyframe_graph(map, {}, window);
  ASSERT_EQ(g.num_edges(), size_t(K - 1 + K - 2));
  for (size_t k = K - 1; k < g.num_edges(); ++k) EXPECT_EQ(g.edges()[k].kind, PoseGraphEdgeKind::odometry);
  PoseGraphOptions o;
  const PoseGraphResult res = g.optimize(o);
  ASSERT_TRUE(res.ok()) << res.message;

  // The linear least squares over x_1 .. x_{K-1}.
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(2 * K - 3, K - 1);
  Eigen::VectorXd b(2 * K - 3);
  int row = 0;
  auto add = [&](int from, int to, double measured, double weight) {
    const double w = std::sqrt(weight);
    if (to > 0) A(row, to - 1) += w;
    if (from > 0) A(row, from - 1) -= w;
    b(row++) = w * measured;
  };
  for (int i = 1; i < K; ++i) add(i - 1, i, d + e, lambda + 1.0);
  for (int i = 2; i < K; ++i) add(i - 2, i, 2 * d, lambda);
  const Eigen::VectorXd x = A.colPivHouseholderQr().solve(b);
  for (int i = 1; i < K; ++i) {
    const SE3& T = res.T_world_node[size_t(i)];
    // Levenberg-Marquardt stops at Ceres' relative tolerances (1e-6 of the cost's decrease), short of the exact
    // minimum by far less than 10 um: 0.5 % of the 2 mm bias per step this is about.
    EXPECT_NEAR(T.translation().x(), x(i - 1), 1e-5) << i;
    EXPECT_NEAR(T.translation().tail<2>().norm(), 0.0, 1e-9) << i;
    EXPECT_NEAR(T.angle_rad(), 0.0, 1e-9) << i;
  }
  // The middle step's error is the infinite chain's e (lambda + 1) / (5 lambda + 1) (the ends' influence decays
  // geometrically: 1 % is reached within the 7 steps from either end), and the end's drift is below half the
  // chain's (K - 1) e.
  const double middle = res.T_world_node[K / 2].translation().x() - res.T_world_node[K / 2 - 1].translation().x();
  EXPECT_NEAR(middle - d, e * (lambda + 1) / (5 * lambda + 1), 0.01 * e / 5);
  EXPECT_LT(res.T_world_node[K - 1].translation().x() - d * (K - 1), 0.5 * (K - 1) * e);

  // The tracked steps join beside the registered chain when asked for, with their information per frame times the
  // scale (plus the floor).
  const PoseGraph tracked = keyframe_graph(map, {}, window, 0.5);
  ASSERT_EQ(tracked.num_edges(), g.num_edges() + size_t(K - 1));
  size_t with_tracked = 0;
  for (const PoseGraphEdge& edge : tracked.edges())
    if (std::abs(edge.information(0, 0) - (0.5 * lambda / 10.0 + 1.0)) < 1e-9) ++with_tracked;
  EXPECT_EQ(with_tracked, size_t(K - 1));
}

TEST(FusedFrames, MovedFramesAreReFusedMostChangedFirst) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(3);  // 80x60
  fusion::VolumeParams vp;
  vp.voxel_m = 0.02;
  vp.capacity_blocks = 1 << 14;
  fusion::VoxelBlockGrid grid(vp);
  DepthImage wall(cam.width, cam.height, 1.0f);  // a plane 1 m in front
  KeyframeMap keys;
  keys.add(0, 0.0, keyframes_pose(0.0), Matrix6d::Identity(), wall, {});
  keys.add(1, 0.1, keyframes_pose(0.1), Matrix6d::Identity(), wall, {});
  FusedFrames fused;
  for (size_t k = 0; k < 2; ++k) {
    fusion::integrate(grid, wall, {}, cam, keys[k].T_world_camera);
    fused.add(k, k, keys[k].T_world_camera, keys[k].T_world_camera, CompressedRgbd::encode(wall, {}, 90));
  }
  fused.schedule(keys, cam, vp.voxel_m);
  EXPECT_EQ(fused.pending(), 0u);  // nothing moved
  keys.set_pose(1, keyframes_pose(0.1 + 0.03));
  fused.schedule(keys, cam, vp.voxel_m);
  ASSERT_EQ(fused.pending(), 1u);
  EXPECT_EQ(fused.step(5, keys, grid, cam, {}, nullptr), 1u);
  EXPECT_EQ(fused.pending(), 0u);
  EXPECT_EQ(fused.refused(), 1u);
  // Re-fused: the map equals fusing both frames at their final poses from scratch.
  fusion::VoxelBlockGrid fresh(vp);
  fusion::integrate(fresh, wall, {}, cam, keys[0].T_world_camera);
  fusion::integrate(fresh, wall, {}, cam, keys[1].T_world_camera);
  EXPECT_EQ(grid.block_count(), fresh.block_count());
  fused.refuse_all(keys, grid, cam, {}, nullptr);
  EXPECT_EQ(grid.block_count(), fresh.block_count());
}

}  // namespace
}  // namespace hf::slam
