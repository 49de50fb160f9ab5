// slam/eval: ATE and RPE against hand-computed cases (evaluate_ate.py / evaluate_rpe.py definitions).
#include "slam/eval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <numbers>
#include <random>

#include "core/error.h"
#include "io/trajectory_io.h"

namespace hf {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180.0;

SE3 eval_pose(const Eigen::Vector3d& t, double yaw_rad = 0.0) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ())), t);
}

// A smooth 3-D path with changing orientation, sampled at `rate_hz` for `duration_s`.
Trajectory helix(double rate_hz, double duration_s, double t0 = 100.0) {
  Trajectory out;
  const int n = int(std::lround(duration_s * rate_hz)) + 1;
  for (int k = 0; k < n; ++k) {
    const double t = k / rate_hz;
    const Eigen::Vector3d p(std::cos(t), std::sin(t), 0.3 * t + 0.05 * t * t);  // not a screw-symmetric helix
    const Eigen::Quaterniond q = Eigen::AngleAxisd(0.7 * t, Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(0.2 * std::sin(t), Eigen::Vector3d::UnitX());
    out.push_back({t0 + t, SE3(q, p)});
  }
  return out;
}

Trajectory transformed(const Trajectory& in, const SE3& T) {
  Trajectory out = in;
  for (StampedPose& p : out) p.T_world_camera = T * p.T_world_camera;
  return out;
}

SE3 some_rigid_motion() {
  const Eigen::Quaterniond q(Eigen::AngleAxisd(0.9, Eigen::Vector3d(1.0, -2.0, 0.5).normalized()));
  return SE3(q, Eigen::Vector3d(3.0, -1.0, 2.5));
}

TEST(ErrorStats, NumpySemantics) {
  // numpy: mean 2.5, median of [1,2,3,4] = 2.5, std (ddof 0) = sqrt(1.25), rmse = sqrt(30/4).
  const ErrorStats s = compute_error_stats({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(s.count, 4u);
  EXPECT_DOUBLE_EQ(s.mean, 2.5);
  EXPECT_DOUBLE_EQ(s.median, 2.5);
  EXPECT_DOUBLE_EQ(s.std, std::sqrt(1.25));
  EXPECT_DOUBLE_EQ(s.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(s.min, 1.0);
  EXPECT_DOUBLE_EQ(s.max, 4.0);
  EXPECT_DOUBLE_EQ(compute_error_stats({5.0, 1.0, 3.0}).median, 3.0);
  EXPECT_EQ(compute_error_stats({}).count, 0u);
  EXPECT_EQ(compute_error_stats({}).rmse, 0.0);
}

// Issue 14.9: finite extreme errors gave NaN and inf statistics; scaled sums keep every statistic finite and exact.
TEST(ErrorStats, FiniteExtremeValuesGiveFiniteStatistics) {
  const ErrorStats s = compute_error_stats({1e308, 1e308, 0.0, 1e308});
  EXPECT_DOUBLE_EQ(s.rmse, 1e308 * std::sqrt(0.75));
  EXPECT_DOUBLE_EQ(s.mean, 0.75e308);
  EXPECT_DOUBLE_EQ(s.std, 1e308 * std::sqrt(3.0) / 4.0);  // sqrt(0.75 * 0.25)
  EXPECT_DOUBLE_EQ(s.median, 1e308);
  EXPECT_DOUBLE_EQ(compute_error_stats({1e-300, 3e-300}).rmse, std::sqrt(5.0) * 1e-300);
}

TEST(FindClosestIndex, AgreesWithBruteForceNearest) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 10.0);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> L(1 + trial % 17);
    for (double& v : L) v = u(rng);
    std::sort(L.begin(), L.end());
    const double t = u(rng) * 1.2 - 1.0;
    size_t best = 0;
    for (size_t k = 1; k < L.size(); ++k) {
      if (std::fabs(L[k] - t) < std::fabs(L[best] - t)) best = k;
    }
    EXPECT_EQ(find_closest_index(L, t), best) << "trial " << trial;
  }
  EXPECT_EQ(find_closest_index({1.0, 2.0, 3.0}, 2.0), 1u);
  EXPECT_EQ(find_closest_index({1.0, 2.0, 3.0}, 99.0), 2u);
  EXPECT_EQ(find_closest_index({1.0, 2.0, 3.0}, -99.0), 0u);
}

TEST(RotationAngle, AccurateNearZeroAndPi) {
  for (double angle : {0.0, 1e-12, 1e-9, 1e-5, 0.3, 2.0, kPi - 1e-6, kPi - 1e-9, kPi}) {
    const Eigen::Quaterniond q(Eigen::AngleAxisd(angle, Eigen::Vector3d(0.2, 0.3, -0.9).normalized()));
    EXPECT_NEAR(rotation_angle_rad(q), angle, 1e-15 + 1e-14 * angle) << angle;
    const Eigen::Quaterniond minus_q(-q.w(), -q.x(), -q.y(), -q.z());
    EXPECT_NEAR(rotation_angle_rad(minus_q), angle, 1e-15 + 1e-14 * angle) << angle;
  }
}

TEST(AlignHorn, RecoversAKnownMotionAndIsOptimal) {
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<Eigen::Vector3d> model, data;
  const SE3 T = some_rigid_motion();
  for (int k = 0; k < 40; ++k) {
    model.emplace_back(g(rng), 2.0 * g(rng), 0.5 * g(rng));
    data.push_back(T * model.back());
  }
  const SE3 exact = align_horn(model, data);
  EXPECT_LT((exact.matrix() - T.matrix()).norm(), 1e-12);

  // With noise the result must be a minimum of sum |R m + t - d|^2: no small rotation about the centroid helps.
  for (auto& d : data) d += 0.05 * Eigen::Vector3d(g(rng), g(rng), g(rng));
  const SE3 fit = align_horn(model, data);
  auto cost = [&](const SE3& S) {
    double c = 0.0;
    for (size_t k = 0; k < model.size(); ++k) c += (S * model[k] - data[k]).squaredNorm();
    return c;
  };
  const double best = cost(fit);
  for (int axis = 0; axis < 6; ++axis) {
    for (double eps : {-1e-4, 1e-4}) {
      Vector6d xi = Vector6d::Zero();
      xi[axis] = eps;
      EXPECT_GT(cost(SE3::exp(xi) * fit), best);
    }
  }
  // A reflection is never returned, even for data that a reflection would fit better.
  std::vector<Eigen::Vector3d> mirrored = model;
  for (auto& m : mirrored) m.z() = -m.z();
  EXPECT_NEAR(align_horn(model, mirrored).rotation().determinant(), 1.0, 1e-12);
  EXPECT_THROW(align_horn({}, {}), Error);
  EXPECT_THROW(align_horn(model, {model[0]}), Error);
}

TEST(Ate, PureTranslationOffsetGivesZero) {
  const Trajectory gt = helix(30.0, 4.0);
  const Trajectory est = transformed(gt, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1.0, 2.0, -3.0)));
  const EvalResult r = evaluate_trajectory(gt, est);
  EXPECT_EQ(r.ate.pairs.size(), gt.size());
  EXPECT_LT(r.ate.error_m.max, 1e-9);
  EXPECT_LT((r.ate.T_gt_est.translation() - Eigen::Vector3d(-1.0, -2.0, 3.0)).norm(), 1e-9);
  EXPECT_FALSE(r.rpe.empty());
  EXPECT_LT(r.rpe.trans_m_per_s.max, 1e-9);
  EXPECT_LT(r.rpe.rot_deg_per_s.max, 1e-9);
}

TEST(Ate, KnownRotationOfTheWholeEstimateGivesZero) {
  const Trajectory gt = helix(30.0, 4.0);
  const SE3 T = some_rigid_motion();
  const EvalResult r = evaluate_trajectory(gt, transformed(gt, T));
  EXPECT_LT(r.ate.error_m.rmse, 1e-9);
  EXPECT_LT((r.ate.T_gt_est.matrix() - T.inverse().matrix()).norm(), 1e-9);
  EXPECT_LT(r.rpe.trans_m_per_s.max, 1e-9);  // relative motions do not see a global transform
  EXPECT_LT(r.rpe.rot_deg_per_s.max, 1e-6);
}

// Radial perturbations of a centred, symmetric point set keep the optimal alignment at the identity (zero mean,
// zero torque, cross-covariance symmetric positive definite), so the per-pose errors are the perturbations.
TEST(Ate, KnownPerturbationsGiveHandComputedStatistics) {
  const std::vector<std::pair<Eigen::Vector3d, double>> points = {
      {{1, 0, 0}, 0.01}, {{0, 2, 0}, -0.03}, {{0, 0, 3}, 0.02}, {{1, 1, 1}, 0.05}};
  const Eigen::Vector3d centre(0.4, -2.0, 1.5);
  Trajectory gt, est_local;
  double stamp = 10.0;
  for (const auto& [g, s] : points) {
    for (double sign : {1.0, -1.0}) {
      gt.push_back({stamp, eval_pose(centre + sign * g)});
      est_local.push_back({stamp, eval_pose(centre + sign * (g + s * g.normalized()))});
      stamp += 0.1;
    }
  }
  // The same estimate seen in another world frame must give the same numbers.
  const Trajectory est = transformed(est_local, some_rigid_motion());
  const AteResult r = evaluate_ate(gt, est);
  ASSERT_EQ(r.pairs.size(), 8u);
  const double expected[] = {0.01, 0.01, 0.03, 0.03, 0.02, 0.02, 0.05, 0.05};
  for (size_t k = 0; k < 8; ++k) EXPECT_NEAR(r.pairs[k].error_m, expected[k], 1e-9) << k;
  // Sorted: .01 .01 .02 .02 | .03 .03 .05 .05.
  EXPECT_NEAR(r.error_m.mean, 0.11 / 4.0, 1e-9);
  EXPECT_NEAR(r.error_m.median, 0.025, 1e-9);
  EXPECT_NEAR(r.error_m.rmse, std::sqrt(39e-4 / 4.0), 1e-9);
  EXPECT_NEAR(r.error_m.std, std::sqrt(39e-4 / 4.0 - 0.0275 * 0.0275), 1e-9);
  EXPECT_NEAR(r.error_m.min, 0.01, 1e-9);
  EXPECT_NEAR(r.error_m.max, 0.05, 1e-9);
}

TEST(Ate, TimestampJitterAssociatesTheNearestGroundTruth) {
  // Ground truth at 100 Hz with a hole at 2.0 .. 2.3 s; the estimate at 30 Hz with +-4 ms jitter, each pose
  // copied from the ground-truth pose nearest in time, so only the right association gives zero error.
  Trajectory gt_full = helix(100.0, 4.0, 0.0), gt;
  for (const StampedPose& p : gt_full) {
    if (p.timestamp_s < 1.995 || p.timestamp_s > 2.305) gt.push_back(p);
  }
  std::vector<double> gt_stamps;
  for (const auto& p : gt) gt_stamps.push_back(p.timestamp_s);
  Trajectory est;
  std::vector<size_t> expected_gt;
  for (int k = 0; k * (1.0 / 30.0) < 3.9; ++k) {
    const double jitter = 0.004 * std::sin(12.9898 * k);
    const double t = k / 30.0 + jitter;
    const size_t nearest = find_closest_index(gt_stamps, t);
    est.push_back({t, gt[nearest].T_world_camera});
    if (std::fabs(gt[nearest].timestamp_s - t) < 0.02) expected_gt.push_back(nearest);
  }
  const AteResult r = evaluate_ate(gt, est);
  ASSERT_EQ(r.pairs.size(), expected_gt.size());
  EXPECT_LT(r.pairs.size(), est.size());  // the poses inside the hole have no partner
  for (size_t k = 0; k < r.pairs.size(); ++k) EXPECT_EQ(r.pairs[k].gt_index, expected_gt[k]);
  EXPECT_LT(r.error_m.max, 1e-9);
}

TEST(Ate, OffsetShiftsTheEstimateStamps) {
  const Trajectory gt = helix(30.0, 3.0);
  Trajectory est = gt;
  for (StampedPose& p : est) p.timestamp_s -= 0.5;
  // Without the offset the stamps still pair up (0.5 s is 15 frames), but with the wrong poses.
  EXPECT_GT(evaluate_ate(gt, est, {.max_difference_s = 0.02, .offset_s = 0.0}).error_m.rmse, 0.01);
  const AteResult r = evaluate_ate(gt, est, {.max_difference_s = 0.02, .offset_s = 0.5});
  EXPECT_EQ(r.pairs.size(), gt.size());
  EXPECT_LT(r.error_m.max, 1e-9);
}

TEST(Ate, ClearErrorsForNoOrTooFewPairs) {
  const Trajectory gt = helix(30.0, 2.0);
  Trajectory far = gt;
  for (StampedPose& p : far) p.timestamp_s += 1000.0;
  try {
    evaluate_ate(gt, far);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no pose pairs within 0.02 s"), std::string::npos) << e.what();
  }
  const Trajectory two(gt.begin(), gt.begin() + 2);
  try {
    evaluate_ate(gt, two);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("at least 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(evaluate_ate(gt, {}), Error);
  EXPECT_THROW(evaluate_ate({}, gt), Error);
  EXPECT_THROW(evaluate_ate(gt, gt, {.max_difference_s = 0.0}), Error);
  EXPECT_THROW(evaluate_ate(gt, gt, {.max_difference_s = NAN}), Error);
}

// Straight line along x at speed v (m/s), sampled at 30 Hz; optional yaw rate (rad/s).
Trajectory line(double v, double yaw_rate = 0.0, double duration_s = 3.0) {
  Trajectory out;
  for (int k = 0; k <= int(std::lround(duration_s * 30.0)); ++k) {
    const double t = k / 30.0;
    out.push_back({50.0 + t, eval_pose(Eigen::Vector3d(v * t, 0.0, 0.0), yaw_rate * t)});
  }
  return out;
}

TEST(Rpe, ConstantVelocityIsExactAndSpeedErrorIsMetresPerSecond) {
  const Trajectory gt = line(0.5);
  const RpeResult same = evaluate_rpe(gt, gt);
  // 91 poses; pose i pairs with i + 30 unless that is the last pose (i >= 60): 60 pairs.
  EXPECT_EQ(same.pairs.size(), 60u);
  EXPECT_EQ(same.rejected_gap_pairs, 0u);
  EXPECT_LT(same.trans_m_per_s.max, 1e-12);
  for (const RpePair& p : same.pairs) EXPECT_EQ(p.est_index_1, p.est_index_0 + 30);

  const RpeResult fast = evaluate_rpe(gt, line(0.6));
  ASSERT_EQ(fast.pairs.size(), 60u);
  for (const RpePair& p : fast.pairs) {
    const double dt = p.est_stamp_1_s - p.est_stamp_0_s;
    EXPECT_NEAR(dt, 1.0, 1e-9);
    EXPECT_NEAR(p.trans_m_per_s, 0.1 * dt, 1e-9);
    EXPECT_NEAR(p.rot_deg_per_s, 0.0, 1e-9);
  }
  EXPECT_NEAR(fast.trans_m_per_s.rmse, 0.1, 1e-9);
  EXPECT_NEAR(fast.trans_m_per_s.mean, 0.1, 1e-9);

  // Reported per second: a 2 s delta sees twice the drift and divides by 2.
  const RpeResult fast2 = evaluate_rpe(gt, line(0.6), {.delta_s = 2.0});
  EXPECT_EQ(fast2.pairs.size(), 30u);
  EXPECT_NEAR(fast2.trans_m_per_s.mean, 0.1, 1e-9);
}

// --delta_unit f: pairs (i, i + delta_frames) of estimated poses, errors per frame. At 30 Hz a 0.1 m/s speed error
// is 0.1 / 30 m per frame; with delta 3 frames the pair sees 3 frames of drift and divides by 3.
TEST(Rpe, FrameUnitsPairEstimatedPosesByIndexAndReportPerFrame) {
  const Trajectory gt = line(0.5);
  for (int delta : {1, 3}) {
    const RpeResult r = evaluate_rpe(gt, line(0.6), {.delta_frames = delta});
    // 91 poses: i + delta must stay below the last index 90.
    ASSERT_EQ(r.pairs.size(), size_t(90 - delta)) << delta;
    for (const RpePair& p : r.pairs) {
      EXPECT_EQ(p.est_index_1, p.est_index_0 + size_t(delta));
      EXPECT_NEAR(p.trans_m_per_s, 0.1 / 30.0, 1e-9);
    }
  }
  EXPECT_THROW(evaluate_rpe(gt, gt, {.delta_frames = -1}), Error);
}

TEST(Rpe, YawRateErrorIsDegreesPerSecond) {
  const Trajectory gt = line(0.0, 10.0 * kDeg);
  const RpeResult r = evaluate_rpe(gt, line(0.0, 13.0 * kDeg));
  ASSERT_EQ(r.pairs.size(), 60u);
  for (const RpePair& p : r.pairs) {
    EXPECT_NEAR(p.rot_deg_per_s, 3.0 * (p.est_stamp_1_s - p.est_stamp_0_s), 1e-9);
    EXPECT_NEAR(p.trans_m_per_s, 0.0, 1e-12);
  }
  EXPECT_NEAR(r.rot_deg_per_s.rmse, 3.0, 1e-9);
  EXPECT_NEAR(r.rot_deg_per_s.mean, 3.0, 1e-9);
}

// The script's error is (E_j^-1 E_i)^-1 (G_j^-1 G_i), not (G_i^-1 G_j)^-1 (E_i^-1 E_j): with a rotating estimate
// and a non-rotating ground truth moving along x at v, the translation of the script's error is
// v dt |Rz(-w t_i) x - Rz(w dt) x| = 2 v dt |sin(w (t_i + dt) / 2)| (t measured from the first pose), where the
// other convention would give 0.
TEST(Rpe, FollowsTheScriptsErrorComposition) {
  const double v = 0.4, w = 20.0 * kDeg;
  const Trajectory gt = line(v), est = line(v, w);
  const RpeResult r = evaluate_rpe(gt, est);
  ASSERT_EQ(r.pairs.size(), 60u);
  for (const RpePair& p : r.pairs) {
    const double ti = p.est_stamp_0_s - 50.0, dt = p.est_stamp_1_s - p.est_stamp_0_s;
    EXPECT_NEAR(p.trans_m_per_s, 2.0 * v * dt * std::fabs(std::sin(w * (ti + dt) / 2.0)), 1e-9);
    EXPECT_NEAR(p.rot_deg_per_s, 20.0 * dt, 1e-9);
  }
}

TEST(Rpe, RejectsPairsWhoseGroundTruthIsBeyondTwiceTheMedianInterval) {
  // Ground truth at 100 Hz over 0 .. 3 s without 1.20 .. 1.69 s; the estimate at 30 Hz. An estimated stamp s has
  // ground truth within 2 x 0.01 s unless 1.21 < s < 1.68, i.e. frames 37 .. 50. Of the 60 pairs (i, i + 30),
  // those with i in 37..50 or i + 30 in 37..50 are rejected: 28.
  Trajectory gt;
  for (int k = 0; k <= 300; ++k) {
    if (k >= 120 && k < 170) continue;
    gt.push_back({50.0 + k * 0.01, eval_pose(Eigen::Vector3d(0.5 * k * 0.01, 0.0, 0.0))});
  }
  const RpeResult r = evaluate_rpe(gt, line(0.5));
  EXPECT_NEAR(r.gt_max_time_difference_s, 0.02, 1e-9);
  EXPECT_EQ(r.rejected_gap_pairs, 28u);
  ASSERT_EQ(r.pairs.size(), 32u);
  for (const RpePair& p : r.pairs) {
    for (size_t i : {p.est_index_0, p.est_index_1}) EXPECT_TRUE(i < 37 || i > 50) << i;
    EXPECT_NEAR(p.trans_m_per_s, 0.0, 0.5 * 0.011);  // nearest-stamp lookup: at most 5 ms of 0.5 m/s per end
  }
}

TEST(Rpe, ShorterThanDeltaHasNoPairsAndNoNaN) {
  const Trajectory gt = line(0.5, 0.0, 0.5);
  const EvalResult r = evaluate_trajectory(gt, gt);
  EXPECT_TRUE(r.rpe.empty());
  const TrajectoryMetrics m = r.metrics();
  EXPECT_EQ(m.rpe_pairs, 0u);
  EXPECT_FALSE(m.rpe_trans_m_per_s.has_value());
  const nlohmann::json j = metrics_to_json(m);
  EXPECT_TRUE(j.at("rpe_trans_rmse_m_per_s").is_null());
  EXPECT_TRUE(j.at("rpe_rot_mean_deg_per_s").is_null());
  EXPECT_EQ(j.at("rpe_pairs"), 0);
  EXPECT_EQ(j.dump().find("NaN"), std::string::npos);
  EXPECT_NE(format_metrics_table(m).find("RPE"), std::string::npos);
  EXPECT_TRUE(evaluate_rpe(gt, {}).empty());
  EXPECT_THROW(evaluate_rpe(gt, gt, {.delta_s = 0.0}), Error);
}

TEST(Metrics, JsonAndMarkdownCarryEveryField) {
  const Trajectory gt = helix(30.0, 3.0);
  Trajectory est = gt;
  for (StampedPose& p : est) {
    p.T_world_camera = SE3(p.T_world_camera.quaternion(), 1.1 * p.T_world_camera.translation());
  }
  const EvalResult r = evaluate_trajectory(gt, est);
  EXPECT_GT(r.ate.error_m.rmse, 0.01);
  EXPECT_GT(r.rpe.rot_deg_per_s.rmse, -1.0);
  const nlohmann::json j = metrics_to_json(r.metrics());
  for (const char* key :
       {"pairs", "ate_rmse_m", "ate_mean_m", "ate_median_m", "ate_std_m", "ate_min_m", "ate_max_m", "rpe_pairs",
        "rpe_trans_rmse_m_per_s", "rpe_trans_mean_m_per_s", "rpe_rot_rmse_deg_per_s", "rpe_rot_mean_deg_per_s"}) {
    ASSERT_TRUE(j.contains(key)) << key;
    EXPECT_TRUE(j.at(key).is_number()) << key;
  }
  EXPECT_EQ(j.at("pairs"), r.ate.pairs.size());
  EXPECT_DOUBLE_EQ(j.at("ate_rmse_m").get<double>(), r.ate.error_m.rmse);
  EXPECT_DOUBLE_EQ(j.at("rpe_rot_mean_deg_per_s").get<double>(), r.rpe.rot_deg_per_s.mean);
  const nlohmann::json per_frame = per_frame_to_json(r);
  EXPECT_EQ(per_frame.at("ate").size(), r.ate.pairs.size());
  EXPECT_EQ(per_frame.at("rpe").size(), r.rpe.pairs.size());
  const std::string md = format_metrics_markdown(r.metrics());
  EXPECT_NE(md.find("| ATE | m |"), std::string::npos) << md;
  EXPECT_NE(md.find("| RPE rot | deg/s |"), std::string::npos) << md;
}

// The real TUM fr1/rpy ground truth (2742 mocap poses at ~100 Hz).
class TumGroundTruth : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string path = std::string(HF_SHARED_DIR) + "/data/tum_fr1_rpy_first150/groundtruth.txt";
    if (!std::filesystem::exists(path)) GTEST_SKIP() << "real TUM data not found at " << path;
    gt_ = read_tum_trajectory(path);
  }
  Trajectory gt_;
};

TEST_F(TumGroundTruth, AgainstItselfIsZero) {
  const EvalResult r = evaluate_trajectory(gt_, gt_);
  EXPECT_EQ(r.ate.pairs.size(), gt_.size());
  EXPECT_LT(r.ate.error_m.max, 1e-9);
  EXPECT_GT(r.rpe.pairs.size(), 2000u);
  EXPECT_EQ(r.rpe.rejected_gap_pairs, 0u);
  EXPECT_LT(r.rpe.trans_m_per_s.max, 1e-9);
  EXPECT_LT(r.rpe.rot_deg_per_s.max, 1e-6);
}

TEST_F(TumGroundTruth, AgainstARigidlyMovedAndTimeShiftedCopyIsZero) {
  Trajectory est = transformed(gt_, some_rigid_motion());
  for (StampedPose& p : est) p.timestamp_s += 0.25;
  const EvalResult r = evaluate_trajectory(gt_, est, {.max_difference_s = 0.02, .offset_s = -0.25});
  EXPECT_EQ(r.ate.pairs.size(), gt_.size());
  EXPECT_LT(r.ate.error_m.max, 1e-9);
  EXPECT_LT((r.ate.T_gt_est.matrix() - some_rigid_motion().inverse().matrix()).norm(), 1e-9);
  EXPECT_LT(r.rpe.trans_m_per_s.max, 1e-9);
  EXPECT_LT(r.rpe.rot_deg_per_s.max, 1e-6);
}

TEST_F(TumGroundTruth, AgainstACopyDelayedByOneSampleMeasuresTheMotion) {
  // est(t_k) = gt(t_{k-1}): the ATE is the (aligned) motion over one ~10 ms step, small but not zero, and the
  // RPE is the difference of the 1 s motions shifted by one sample.
  Trajectory est;
  for (size_t k = 1; k < gt_.size(); ++k) est.push_back({gt_[k].timestamp_s, gt_[k - 1].T_world_camera});
  const EvalResult r = evaluate_trajectory(gt_, est);
  EXPECT_EQ(r.ate.pairs.size(), est.size());
  EXPECT_GT(r.ate.error_m.rmse, 1e-4);
  EXPECT_LT(r.ate.error_m.rmse, 0.02);
  EXPECT_GT(r.rpe.rot_deg_per_s.mean, 0.01);
  // The unaligned per-pose error bounds the aligned RMSE from above (alignment minimises it).
  double sum_sq = 0.0;
  for (const AtePair& p : r.ate.pairs) {
    sum_sq +=
        (gt_[p.gt_index].T_world_camera.translation() - est[p.est_index].T_world_camera.translation()).squaredNorm();
  }
  EXPECT_LE(r.ate.error_m.rmse, std::sqrt(sum_sq / double(r.ate.pairs.size())) + 1e-12);
}

}  // namespace
}  // namespace hf
