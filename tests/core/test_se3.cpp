#include "core/se3.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <cmath>
#include <limits>
#include <random>

namespace hf {
namespace {

constexpr double kPi = 3.14159265358979323846;

Vector6d random_xi(std::mt19937& rng, double max_angle) {
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> angle(0.0, max_angle);
  Eigen::Vector3d axis(n(rng), n(rng), n(rng));
  Vector6d xi;
  xi.head<3>() = axis.normalized() * angle(rng);
  xi.tail<3>() = Eigen::Vector3d(n(rng), n(rng), n(rng));
  return xi;
}

SE3 random_pose(std::mt19937& rng) { return SE3::exp(random_xi(rng, 3.0)); }

double matrix_distance(const SE3& a, const SE3& b) { return (a.matrix() - b.matrix()).norm(); }

// The 4x4 twist matrix [[omega]x v; 0 0].
Eigen::Matrix4d hat(const Vector6d& xi) {
  Eigen::Matrix4d A = Eigen::Matrix4d::Zero();
  A.topLeftCorner<3, 3>() = skew(xi.head<3>());
  A.topRightCorner<3, 1>() = xi.tail<3>();
  return A;
}

// Reference matrix exponential by scaling and squaring of the Taylor series: exp(A) = exp(A / 2^s)^(2^s) with
// |A / 2^s| <= 1/2, where 25 terms leave a truncation error below 0.5^26 / 26! ~ 1e-34.
Eigen::Matrix4d expm_series(const Eigen::Matrix4d& A) {
  int s = 0;
  double norm = A.norm();
  while (norm > 0.5) {
    norm *= 0.5;
    ++s;
  }
  const Eigen::Matrix4d B = A / std::ldexp(1.0, s);
  Eigen::Matrix4d sum = Eigen::Matrix4d::Identity(), term = Eigen::Matrix4d::Identity();
  for (int k = 1; k <= 25; ++k) {
    term = term * B / double(k);
    sum += term;
  }
  for (int i = 0; i < s; ++i) sum = sum * sum;
  return sum;
}

TEST(SE3, ExpMatchesSeriesMatrixExponentialOfTwist) {
  std::mt19937 rng(1);
  for (int i = 0; i < 200; ++i) {
    const Vector6d xi = random_xi(rng, 3.1);
    const Eigen::Matrix4d A = hat(xi);
    // Each of the s squarings roughly doubles the relative rounding error of the series (~ 1e-16 |exp(A)|), so
    // the reference is accurate to ~ 2^s * 1e-16 * (1 + |A|)^2 with 2^s <= 2 |A|: 1e-12 covers |A| < 10.
    const double tol = 1e-13 * (1.0 + A.norm()) * (1.0 + A.norm()) * (1.0 + A.norm());
    EXPECT_LT((SE3::exp(xi).matrix() - expm_series(A)).norm(), tol) << xi.transpose();
  }
  // Small and zero rotations (the Taylor branches).
  for (double angle : {0.0, 1e-12, 1e-9, 1e-6, 9.9e-6, 1.01e-5, 1e-3}) {
    Vector6d xi;
    xi << angle * 0.6, -angle * 0.8, 0.0, 0.3, -1.2, 2.0;
    EXPECT_LT((SE3::exp(xi).matrix() - expm_series(hat(xi))).norm(), 1e-14) << angle;
  }
}

TEST(SE3, ExpLogRoundTrip) {
  std::mt19937 rng(2);
  for (int i = 0; i < 500; ++i) {
    const Vector6d xi = random_xi(rng, 3.0);
    EXPECT_LT((SE3::exp(xi).log() - xi).norm(), 1e-10) << xi.transpose();
    const SE3 T = random_pose(rng);
    EXPECT_LT(matrix_distance(SE3::exp(T.log()), T), 1e-12);
  }
}

// Sweeps the rotation angle over the Taylor/closed-form switch (1e-5) and beyond: exp and log must stay accurate
// to a few ulps everywhere (a 1 - cos(t) cancellation once made log's translation wrong by 1e-6 near 1e-5).
TEST(SE3, ExpLogAccurateAcrossSmallAngleSwitch) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.36, -0.48, 0.8);
  const Eigen::Vector3d v(0.7, -1.3, 2.1);
  for (double angle = 1e-8; angle < 1.0; angle *= 1.37) {
    Vector6d xi;
    xi.head<3>() = axis * angle;
    xi.tail<3>() = v;
    const Vector6d back = SE3::exp(xi).log();
    EXPECT_LT((back.head<3>() - xi.head<3>()).norm(), 1e-15 + 1e-14 * angle) << angle;
    EXPECT_LT((back.tail<3>() - v).norm(), 1e-14) << angle;
    EXPECT_LT((SE3::exp(xi).matrix() - expm_series(hat(xi))).norm(), 1e-14) << angle;
  }
}

TEST(SE3, TinyAnglesKeepFullRelativePrecision) {
  for (double angle : {1e-9, 1e-12, 1e-15}) {
    Vector6d xi;
    xi << angle * 2.0 / 3.0, angle / 3.0, -angle * 2.0 / 3.0, 0.5, -0.25, 1.0;
    const SE3 T = SE3::exp(xi);
    const Vector6d back = T.log();
    // Relative, not absolute: the rotation part must survive even though it is far below 1e-9 of the translation.
    EXPECT_LT((back.head<3>() - xi.head<3>()).norm(), 1e-6 * angle) << angle;
    EXPECT_LT((back.tail<3>() - xi.tail<3>()).norm(), 1e-12);
    EXPECT_NEAR(T.angle_rad(), angle, 1e-6 * angle);
  }
  EXPECT_EQ(SE3::exp(Vector6d::Zero()).log(), Vector6d::Zero());
}

TEST(SE3, AnglesNearPi) {
  const Eigen::Vector3d axis = Eigen::Vector3d(1.0, -2.0, 0.5).normalized();
  for (double delta : {1e-3, 1e-6, 1e-9, 0.0}) {
    Vector6d xi;
    xi.head<3>() = axis * (kPi - delta);
    xi.tail<3>() = Eigen::Vector3d(0.2, 0.4, -0.6);
    const SE3 T = SE3::exp(xi);
    EXPECT_NEAR(T.angle_rad(), kPi - delta, 1e-8);
    // Near pi the axis sign is ambiguous only at exactly pi, so compare transforms, plus xi away from pi.
    EXPECT_LT(matrix_distance(SE3::exp(T.log()), T), 1e-9) << delta;
    if (delta >= 1e-6) {
      EXPECT_LT((T.log() - xi).norm(), 1e-7) << delta;
    }
    EXPECT_LE(T.log().head<3>().norm(), kPi + 1e-12);
  }
}

TEST(SE3, CompositionInverseAndPoints) {
  std::mt19937 rng(3);
  for (int i = 0; i < 100; ++i) {
    const SE3 a = random_pose(rng), b = random_pose(rng), c = random_pose(rng);
    EXPECT_LT(matrix_distance((a * b) * c, a * (b * c)), 1e-12);
    EXPECT_LT((((a * b).matrix()) - a.matrix() * b.matrix()).norm(), 1e-12);
    EXPECT_LT(matrix_distance(a * a.inverse(), SE3::identity()), 1e-13);
    EXPECT_LT(matrix_distance(a.inverse() * a, SE3::identity()), 1e-13);
    EXPECT_LT(matrix_distance((a * b).inverse(), b.inverse() * a.inverse()), 1e-12);
    const Eigen::Vector3d p(0.3, -1.0, 2.0);
    EXPECT_LT(((a * p) - (a.matrix() * p.homogeneous()).head<3>()).norm(), 1e-12);
    EXPECT_LT((a.inverse() * (a * p) - p).norm(), 1e-12);
    EXPECT_NEAR(a.quaternion().norm(), 1.0, 1e-15);
  }
}

TEST(SE3, InterpolateEndpointsAndMidpoint) {
  std::mt19937 rng(4);
  for (int i = 0; i < 100; ++i) {
    const SE3 a = random_pose(rng), b = random_pose(rng);
    EXPECT_LT(matrix_distance(SE3::interpolate(a, b, 0.0), a), 1e-12);
    EXPECT_LT(matrix_distance(SE3::interpolate(a, b, 1.0), b), 1e-9);
    // The midpoint splits the relative motion into two equal halves: a^-1 m == m^-1 b.
    const SE3 m = SE3::interpolate(a, b, 0.5);
    EXPECT_LT(matrix_distance(a.inverse() * m, m.inverse() * b), 1e-9);
    EXPECT_NEAR((a.inverse() * m).angle_rad(), 0.5 * (a.inverse() * b).angle_rad(), 1e-9);
  }
  // Pure translation interpolates linearly.
  const SE3 t0(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 0, 0));
  const SE3 t1(Eigen::Quaterniond::Identity(), Eigen::Vector3d(2, -4, 6));
  EXPECT_LT((SE3::interpolate(t0, t1, 0.25).translation() - Eigen::Vector3d(0.5, -1, 1.5)).norm(), 1e-15);
}

TEST(SE3, FromMatrixReorthonormalises) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1e-3);
  for (int i = 0; i < 50; ++i) {
    const SE3 T = random_pose(rng);
    EXPECT_LT(matrix_distance(SE3::from_matrix(T.matrix()), T), 1e-12);
    Eigen::Matrix4d M = T.matrix();
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M(r, c) += n(rng);
    const SE3 U = SE3::from_matrix(M);
    const Eigen::Matrix3d R = U.rotation();
    EXPECT_LT((R.transpose() * R - Eigen::Matrix3d::Identity()).norm(), 1e-12);
    EXPECT_NEAR(R.determinant(), 1.0, 1e-12);
    // The nearest rotation is within the size of the perturbation (Frobenius norm ~ 3e-3).
    EXPECT_LT((R - T.rotation()).norm(), 1e-2);
    EXPECT_EQ(U.translation(), T.translation());
  }
  // A reflection is turned into the nearest proper rotation.
  Eigen::Matrix4d F = Eigen::Matrix4d::Identity();
  F(2, 2) = -1.0;
  EXPECT_NEAR(SE3::from_matrix(F).rotation().determinant(), 1.0, 1e-12);
}

TEST(SE3, SkewSo3AndFiniteness) {
  const Eigen::Vector3d w(0.1, -0.2, 0.3), v(1.0, 2.0, -1.0);
  EXPECT_LT((skew(w) * v - w.cross(v)).norm(), 1e-15);
  EXPECT_LT((so3_log(so3_exp(w)) - w).norm(), 1e-14);
  EXPECT_TRUE(SE3::identity().is_finite());
  Vector6d bad = Vector6d::Zero();
  bad(3) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(SE3::exp(bad).is_finite());
  EXPECT_EQ(SE3::identity().angle_rad(), 0.0);
}

}  // namespace
}  // namespace hf
