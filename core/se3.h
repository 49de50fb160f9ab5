// Rigid transforms SE(3) on Eigen, in double.
//
// Conventions (used everywhere in hashfusion):
// - A transform is named by its frames: T_world_camera maps points in the camera frame into the world frame,
//   p_world = T_world_camera * p_camera. Composition chains frames: T_a_c = T_a_b * T_b_c.
// - The incremental motion of the registration report (equations 10-11): T^(t+1) = T^(t) * delta_T, so
//   delta_T = (T^(t))^-1 * T^(t+1) maps points of camera t+1 into camera t.
// - Tangent vectors xi = (omega, v) in R^6, rotation first as in equation 17. exp(xi) is the exact SE(3)
//   exponential: R = exp([omega]x) by Rodrigues, t = V(omega) v with V the left Jacobian of SO(3). Both use
//   Taylor branches below |omega| = 1e-5 where the closed forms lose precision.
// - The rotation is stored as a unit quaternion (normalised after every composition).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace hf {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

class SE3 {
 public:
  SE3() : q_(Eigen::Quaterniond::Identity()), t_(Eigen::Vector3d::Zero()) {}
  SE3(const Eigen::Quaterniond& q, const Eigen::Vector3d& t) : q_(q.normalized()), t_(t) {}
  SE3(const Eigen::Matrix3d& R, const Eigen::Vector3d& t) : q_(Eigen::Quaterniond(R).normalized()), t_(t) {}
  // From a 4x4 homogeneous matrix; the rotation block is re-orthonormalised (nearest rotation by SVD).
  static SE3 from_matrix(const Eigen::Matrix4d& T);
  static SE3 identity() { return SE3(); }

  static SE3 exp(const Vector6d& xi);
  Vector6d log() const;

  const Eigen::Quaterniond& quaternion() const { return q_; }
  Eigen::Matrix3d rotation() const { return q_.toRotationMatrix(); }
  const Eigen::Vector3d& translation() const { return t_; }
  Eigen::Matrix4d matrix() const;
  Eigen::Matrix4f matrixf() const { return matrix().cast<float>(); }

  SE3 inverse() const;
  SE3 operator*(const SE3& other) const;
  Eigen::Vector3d operator*(const Eigen::Vector3d& p) const { return q_ * p + t_; }

  // Geodesic interpolation: a * exp(alpha * log(a^-1 b)); alpha = 0 gives a, alpha = 1 gives b.
  static SE3 interpolate(const SE3& a, const SE3& b, double alpha);

  // Rotation angle of this transform in radians, in [0, pi].
  double angle_rad() const;
  bool is_finite() const;

 private:
  Eigen::Quaterniond q_;
  Eigen::Vector3d t_;
};

// [w]x, the skew-symmetric cross-product matrix.
Eigen::Matrix3d skew(const Eigen::Vector3d& w);
// SO(3) exponential and logarithm (axis-angle vector, |w| <= pi).
Eigen::Matrix3d so3_exp(const Eigen::Vector3d& w);
Eigen::Vector3d so3_log(const Eigen::Matrix3d& R);

}  // namespace hf
