#include "core/se3.h"

#include <Eigen/SVD>
#include <cmath>

namespace hf {
namespace {
// Below this rotation angle the closed forms divide small by small; the Taylor series to the orders used here
// are exact to double precision (next term ~ theta^4 / 5040 < 1e-23).
constexpr double kSmallAngle = 1e-5;

// Left Jacobian of SO(3): V = I + (1 - cos t)/t^2 [w]x + (t - sin t)/t^3 [w]x^2.
Eigen::Matrix3d so3_left_jacobian(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d W = skew(w);
  double a, b;
  if (theta < kSmallAngle) {
    a = 0.5 - theta2 / 24.0;
    b = 1.0 / 6.0 - theta2 / 120.0;
  } else {
    // 1 - cos t = 2 sin^2(t/2): the direct form cancels catastrophically for small t (relative error eps / t^2,
    // 1e-6 just above kSmallAngle).
    const double s = std::sin(0.5 * theta);
    a = 2.0 * s * s / theta2;
    b = (theta - std::sin(theta)) / (theta2 * theta);
  }
  return Eigen::Matrix3d::Identity() + a * W + b * W * W;
}

// Inverse of the left Jacobian: V^-1 = I - 1/2 [w]x + (1/t^2)(1 - (t sin t) / (2 (1 - cos t))) [w]x^2.
Eigen::Matrix3d so3_left_jacobian_inverse(const Eigen::Vector3d& w) {
  const double theta2 = w.squaredNorm();
  const double theta = std::sqrt(theta2);
  const Eigen::Matrix3d W = skew(w);
  double c;
  if (theta < kSmallAngle) {
    c = 1.0 / 12.0 + theta2 / 720.0;
  } else {
    // t sin t / (2 (1 - cos t)) = (t/2) cot(t/2). Written with 1 - cos t, the ratio inherits that difference's
    // relative error eps / t^2, which the subtraction from 1 and the division by t^2 turn into an error of
    // eps / t^4 in c (log's translation was off by ~1e-6 |t| just above kSmallAngle).
    const double half = 0.5 * theta;
    c = (1.0 - half * std::cos(half) / std::sin(half)) / theta2;
  }
  return Eigen::Matrix3d::Identity() - 0.5 * W + c * W * W;
}
}  // namespace

Eigen::Matrix3d skew(const Eigen::Vector3d& w) {
  Eigen::Matrix3d S;
  S << 0.0, -w.z(), w.y(), w.z(), 0.0, -w.x(), -w.y(), w.x(), 0.0;
  return S;
}

Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  if (theta < kSmallAngle) {
    const Eigen::Matrix3d W = skew(w);
    return Eigen::Matrix3d::Identity() + W + 0.5 * W * W;
  }
  return Eigen::AngleAxisd(theta, w / theta).toRotationMatrix();
}

Eigen::Vector3d so3_log(const Eigen::Matrix3d& R) {
  // Through the quaternion: 2 atan2(|v|, w) is accurate over the whole range, including near pi where the
  // trace formula's acos loses half the digits.
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double vn = q.vec().norm();
  if (vn < 1e-12) return 2.0 * q.vec();  // theta ~ 2 |v| for tiny angles
  const double theta = 2.0 * std::atan2(vn, q.w());
  return q.vec() * (theta / vn);
}

SE3 SE3::from_matrix(const Eigen::Matrix4d& T) {
  Eigen::JacobiSVD<Eigen::Matrix3d> svd(T.topLeftCorner<3, 3>(), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0.0) {
    Eigen::Matrix3d U = svd.matrixU();
    U.col(2) *= -1.0;
    R = U * svd.matrixV().transpose();
  }
  return SE3(R, T.topRightCorner<3, 1>());
}

SE3 SE3::exp(const Vector6d& xi) {
  const Eigen::Vector3d w = xi.head<3>();
  const Eigen::Vector3d v = xi.tail<3>();
  return SE3(so3_exp(w), so3_left_jacobian(w) * v);
}

Vector6d SE3::log() const {
  const Eigen::Vector3d w = so3_log(rotation());
  Vector6d xi;
  xi.head<3>() = w;
  xi.tail<3>() = so3_left_jacobian_inverse(w) * t_;
  return xi;
}

Eigen::Matrix4d SE3::matrix() const {
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() = rotation();
  T.topRightCorner<3, 1>() = t_;
  return T;
}

SE3 SE3::inverse() const {
  const Eigen::Quaterniond qi = q_.conjugate();
  return SE3(qi, -(qi * t_));
}

SE3 SE3::operator*(const SE3& o) const { return SE3(q_ * o.q_, q_ * o.t_ + t_); }

SE3 SE3::interpolate(const SE3& a, const SE3& b, double alpha) {
  return a * SE3::exp(alpha * (a.inverse() * b).log());
}

double SE3::angle_rad() const { return so3_log(rotation()).norm(); }

bool SE3::is_finite() const { return q_.coeffs().allFinite() && t_.allFinite(); }

}  // namespace hf
