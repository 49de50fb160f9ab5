// The sparse registration's parts (registration/sparse/feature_matcher.h, rigid_ransac.h) and the method on the
// cases it exists for: the wide baseline of the `fast` preset, and textureless frames, where it must say it cannot.
#include <gtest/gtest.h>

#include <random>

#include "reg_test_util.h"
#include "registration/sparse.h"

namespace hf {
namespace {

// Noise-free points with exact correspondences: the closed form is exact to rounding; collinear points have no
// unique rotation and are refused.
TEST(Sparse, WeightedRigidFitIsExactAndRefusesCollinearPoints) {
  const SE3 T_true = SE3::exp((Vector6d() << 0.1, -0.2, 0.3, 0.05, -0.4, 0.2).finished());
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Eigen::Vector3d> p, q;
  std::vector<double> w;
  for (int i = 0; i < 20; ++i) {
    p.emplace_back(u(rng), u(rng), 2.0 + u(rng));
    q.push_back(T_true * p.back());
    w.push_back(0.5 + 0.5 * (u(rng) + 1.0));
  }
  SE3 T;
  ASSERT_TRUE(fit_rigid_weighted(p, q, w, &T));
  EXPECT_LT(test::translation_error_m(T, T_true), 1e-12);
  EXPECT_LT(test::rotation_error_deg(T, T_true), 1e-10);
  std::vector<Eigen::Vector3d> line_p, line_q;
  for (int i = 0; i < 5; ++i) {
    line_p.emplace_back(0.1 * i, 0.2 * i, 2.0);
    line_q.push_back(T_true * line_p.back());
  }
  SE3 untouched;
  EXPECT_FALSE(fit_rigid_weighted(line_p, line_q, std::vector<double>(5, 1.0), &untouched));
  EXPECT_LT(test::translation_error_m(untouched, SE3()), 0.0 + 1e-15);
  EXPECT_FALSE(fit_rigid_weighted({}, {}, {}, &untouched));
}

// 200 correspondences drawn with the noise model's covariance, 40 % of them replaced by random points: RANSAC keeps
// the true ones (an outlier passes the 99 % chi-square test only by landing within ~3 sigma, rare for points spread
// over metres) and loses about 1 % of the inliers to the test. The refined motion is within the noise: its error
// delta = log(T_est T_true^-1) lies inside the 99.9 % ellipsoid of its own information, delta^T H delta < chi2_6
// (22.46), and the information is the inverse covariance of the estimate, so that is the test of both.
TEST(Sparse, RansacRejectsOutliersAndRefinesWithinTheNoise) {
  const SE3 T_true = SE3::exp((Vector6d() << 0.05, 0.26, -0.02, 0.1, 0.02, -0.05).finished());  // 15 deg, 10 cm
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::normal_distribution<double> g(0.0, 1.0);
  std::vector<PointPair> pairs;
  std::vector<bool> outlier;
  for (int i = 0; i < 200; ++i) {
    PointPair pair;
    pair.current = Eigen::Vector3d(1.5 * u(rng), 1.0 * u(rng), 2.5 + u(rng));
    pair.Sigma_current = depth_point_covariance(pair.current, 1.0, 262.5);
    const Eigen::Vector3d q = T_true * pair.current;
    pair.Sigma_reference = depth_point_covariance(q, 1.0, 262.5);
    const bool bad = i % 5 < 2;
    if (bad) {
      pair.reference = Eigen::Vector3d(1.5 * u(rng), 1.0 * u(rng), 2.5 + u(rng));
    } else {
      const Eigen::Matrix3d C = T_true.rotation() * pair.Sigma_current * T_true.rotation().transpose() +
                                pair.Sigma_reference;
      const Eigen::Matrix3d L = C.llt().matrixL();
      pair.reference = q + L * Eigen::Vector3d(g(rng), g(rng), g(rng));
    }
    pairs.push_back(pair);
    outlier.push_back(bad);
  }
  const RigidEstimate est = estimate_rigid_ransac(pairs);
  ASSERT_TRUE(est.ok);
  int true_inliers = 0, false_inliers = 0;
  for (const int i : est.inliers) (outlier[size_t(i)] ? false_inliers : true_inliers)++;
  std::printf("inliers %d true, %d false, %d hypotheses; error %.3f mm %.4f deg\n", true_inliers, false_inliers,
              est.hypotheses, test::translation_error_m(est.T_ref_cur, T_true) * 1e3,
              test::rotation_error_deg(est.T_ref_cur, T_true));
  EXPECT_LE(false_inliers, 2);
  EXPECT_GE(true_inliers, 114);  // of 120: the 99 % test keeps 118.8 on average
  const Vector6d delta = (est.T_ref_cur * T_true.inverse()).log();
  const double d2 = delta.dot(est.JtJ * delta);
  std::printf("Mahalanobis distance^2 of the error: %.2f\n", d2);
  EXPECT_LT(d2, 22.46);
  // ~1 cm point noise over 120 points at a 2.5 m lever arm: a few millimetres, a few hundredths of a degree.
  EXPECT_LT(test::translation_error_m(est.T_ref_cur, T_true), 6e-3);
  EXPECT_LT(test::rotation_error_deg(est.T_ref_cur, T_true), 0.15);
  EXPECT_TRUE(est.JtJ.allFinite());
  // Too few pairs: no estimate, no exception.
  EXPECT_FALSE(estimate_rigid_ransac(std::vector<PointPair>(pairs.begin(), pairs.begin() + 2)).ok);
}

// A frame matched against itself: every feature is its own best match (distance 0) and passes the cross-check,
// except where two features share a descriptor (the ratio test then rejects both).
TEST(Sparse, FeaturesMatchThemselves) {
  const test::FramePair pair = test::make_pair("room", 10, 11, false);
  const FeatureFrame f = extract_features(pair.reference.levels[0]);
  ASSERT_GE(f.features.size(), 100u);
  for (const Feature& x : f.features) {
    EXPECT_TRUE(x.point_m.allFinite());
    EXPECT_GT(x.point_m.z(), 0.0);
  }
  const std::vector<FeatureMatch> m = match_features(f, f);
  EXPECT_GE(m.size(), f.features.size() * 9 / 10);
  for (const FeatureMatch& x : m) {
    EXPECT_EQ(x.current, x.reference);
    EXPECT_EQ(x.distance_bits, 0);
  }
  FramePyramidLevel grey = pair.reference.levels[0];
  grey.intensity = IntensityImage();
  EXPECT_TRUE(extract_features(grey).empty());
}

RegistrationResult align_sparse(const test::FramePair& pair) {
  const RegistrationResult r = make_registration("sparse")->align(pair.current, pair.reference, SE3());
  test::expect_finite(r);
  std::printf("sparse: %s, %ld inliers (ratio %.2f), error %.3f mm %.4f deg (motion %.1f mm %.2f deg) %s\n",
              to_string(r.status), r.inliers, r.inlier_ratio,
              test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true) * 1e3,
              test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true),
              pair.T_ref_cur_true.translation().norm() * 1e3,
              pair.T_ref_cur_true.angle_rad() * 180 / std::numbers::pi, r.message.c_str());
  return r;
}

// 15 degrees and 10 cm between frames, from the identity: no basin to be in. The error is keypoint localisation
// (sub-pixel noise over ~100 inliers): a few millimetres and a few tenths of a degree, under the registry's 1 cm /
// 0.5 deg for fast motion (test_hard_cases.cpp).
TEST(Sparse, TracksTheWideBaseline) {
  for (const int i : {3, 20, 40}) {
    const test::FramePair pair = test::make_pair("fast", i, i + 1, true);
    const RegistrationResult r = align_sparse(pair);
    EXPECT_EQ(r.status, RegistrationStatus::good) << r.message;
    EXPECT_GE(r.inliers, 30);
    EXPECT_LT(test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true), 0.01);
    EXPECT_LT(test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true), 0.5);
    EXPECT_EQ(r.degenerate_dims, 0);
    // The information is J^T C^-1 J of the inliers: symmetric positive definite.
    EXPECT_LT((r.information - r.information.transpose()).norm(), 1e-9 * r.information.norm());
    EXPECT_GT(r.eigenvalues(0), 0.0);
  }
}

// One uniform colour: no texture, no features: a status, never a guess (the initial guess comes back).
TEST(Sparse, TexturelessIsAStatusNotAGuess) {
  const test::FramePair pair = test::make_pair("textureless", 10, 11, true);
  const SE3 guess = SE3::exp((Vector6d() << 0.0, 0.01, 0.0, 0.02, 0.0, 0.0).finished());
  const RegistrationResult r = make_registration("sparse")->align(pair.current, pair.reference, guess);
  test::expect_finite(r);
  std::printf("textureless: %s, %ld inliers: %s\n", to_string(r.status), r.inliers, r.message.c_str());
  EXPECT_FALSE(r.usable());
  EXPECT_FALSE(r.message.empty());
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, guess), 1e-12);
}

}  // namespace
}  // namespace hf
