// RPE per consecutive frame pair (bench/harness/frame_rpe.h), evaluate_rpe.py --fixed_delta --delta 1
// --delta_unit f: hand-computed errors on small trajectories, the script's pair rules, and agreement with the
// per-second RPE of slam/eval.h when one frame interval is the delta.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "bench/harness/frame_rpe.h"
#include "slam/eval.h"

namespace hf::bench {
namespace {

constexpr double kDt = 1.0 / 30.0;

// n poses at 30 Hz moving 1 cm per frame along z, no rotation.
Trajectory straight_line(int n) {
  Trajectory t;
  for (int k = 0; k < n; ++k) t.push_back({k * kDt, SE3(Eigen::Quaterniond::Identity(), {0.0, 0.0, 0.01 * k})});
  return t;
}

TEST(FrameRpe, ExactEstimateHasZeroErrorAndDropsThePairEndingOnTheLastPose) {
  const Trajectory gt = straight_line(5);
  const FrameRpe r = evaluate_rpe_per_frame(gt, gt);
  EXPECT_EQ(r.pairs, 3u);  // (0,1), (1,2), (2,3): the script keeps no pair whose partner is the last pose
  EXPECT_EQ(r.rejected_gap_pairs, 0u);
  EXPECT_NEAR(r.trans_m.rmse, 0.0, 1e-12);
  EXPECT_NEAR(r.rot_deg.rmse, 0.0, 1e-9);
}

// Pose 2 displaced by d: pairs (1,2) and (2,3) each carry |d| (errors (e_j - e_i) + (g_i - g_j) = +d, -d), pair (0,1)
// none, so the RMSE over the three pairs is |d| sqrt(2/3).
TEST(FrameRpe, OneDisplacedPose) {
  const Trajectory gt = straight_line(5);
  Trajectory est = gt;
  const Eigen::Vector3d d(0.003, -0.004, 0.0);  // 5 mm
  est[2].T_world_camera = SE3(Eigen::Quaterniond::Identity(), est[2].T_world_camera.translation() + d);
  const FrameRpe r = evaluate_rpe_per_frame(gt, est);
  ASSERT_EQ(r.pairs, 3u);
  EXPECT_NEAR(r.trans_m.rmse, 0.005 * std::sqrt(2.0 / 3.0), 1e-12);
  EXPECT_NEAR(r.trans_m.max, 0.005, 1e-12);
  EXPECT_NEAR(r.trans_m.min, 0.0, 1e-12);
}

// A rotation drift of theta per frame about the optical axis (E_k = G_k Rz(k theta)) with motion along that axis:
// every pair's error is exactly Rz(theta) with no translation.
TEST(FrameRpe, RotationDriftPerFrame) {
  const Trajectory gt = straight_line(6);
  Trajectory est = gt;
  const double theta = 0.5 * std::numbers::pi / 180.0;
  for (size_t k = 0; k < est.size(); ++k) {
    est[k].T_world_camera =
        est[k].T_world_camera *
        SE3(Eigen::Quaterniond(Eigen::AngleAxisd(double(k) * theta, Eigen::Vector3d::UnitZ())), Eigen::Vector3d::Zero());
  }
  const FrameRpe r = evaluate_rpe_per_frame(gt, est);
  ASSERT_EQ(r.pairs, 4u);
  EXPECT_NEAR(r.rot_deg.rmse, 0.5, 1e-9);
  EXPECT_NEAR(r.trans_m.rmse, 0.0, 1e-12);
}

// A pair whose end has no ground truth within 2 x the median interval is rejected, as in the script; with fewer
// than three poses there is no pair at all.
TEST(FrameRpe, GapsAndShortTrajectories) {
  const Trajectory gt = straight_line(5);
  Trajectory est(gt.begin(), gt.begin() + 3);
  est.push_back({10.0, gt[3].T_world_camera});  // far beyond the ground truth
  est.push_back({10.0 + kDt, gt[4].T_world_camera});
  const FrameRpe r = evaluate_rpe_per_frame(gt, est);
  EXPECT_EQ(r.pairs, 2u);  // (0,1), (1,2); (2,3) rejected; (3,4) ends on the last pose
  EXPECT_EQ(r.rejected_gap_pairs, 1u);
  EXPECT_TRUE(evaluate_rpe_per_frame(gt, Trajectory(gt.begin(), gt.begin() + 2)).empty());
  EXPECT_TRUE(evaluate_rpe_per_frame({}, gt).empty());
}

// With stamps exactly one interval apart, slam/eval.h's RPE over delta = one interval picks the same pairs (the
// nearest stamp to t_i + dt is t_{i+1}) and reports the error divided by dt.
TEST(FrameRpe, AgreesWithThePerSecondRpeAtOneFrameInterval) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.002);
  Trajectory gt, est;
  for (int k = 0; k < 40; ++k) {
    const SE3 g = SE3::exp((Vector6d() << 0.01 * k, 0.02 * std::sin(0.1 * k), 0.0, 0.01 * k, 0.0, 0.005 * k).finished());
    Vector6d n;
    for (int a = 0; a < 6; ++a) n[a] = noise(rng);
    gt.push_back({k * kDt, g});
    est.push_back({k * kDt, g * SE3::exp(n)});
  }
  const FrameRpe frames = evaluate_rpe_per_frame(gt, est);
  const RpeResult seconds = evaluate_rpe(gt, est, {.delta_s = kDt});
  ASSERT_EQ(frames.pairs, seconds.pairs.size());
  EXPECT_NEAR(frames.trans_m.rmse, seconds.trans_m_per_s.rmse * kDt, 1e-12);
  EXPECT_NEAR(frames.rot_deg.rmse, seconds.rot_deg_per_s.rmse * kDt, 1e-9);
  EXPECT_GT(frames.trans_m.rmse, 0.0);
}

}  // namespace
}  // namespace hf::bench
