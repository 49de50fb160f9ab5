// Rigid motion from 3-D point correspondences: the weighted closed-form fit (Umeyama 1991 without scale, i.e.
// Kabsch), RANSAC over minimal 3-point fits with an inlier test from the depth noise model, and a least-squares
// refinement on the inliers (the sparse registration's estimator, registration/sparse.h).
//
// Frames: correspondences pair a current-camera point p with a reference-camera point q; the estimate T_ref_cur
// maps p onto q (q = R p + t), as every registration result does.
//
// Noise model: a point measured at depth z along the unit ray r has covariance
//   Sigma = sigma_l^2 (I - r r^T) + sigma_z^2 r r^T,  sigma_z = hf_kinect_axial_sigma_m(z) (Nguyen et al. 2012),
//   sigma_l = z * keypoint_sigma_px * scale / f     (keypoint localisation, growing with the ORB octave's scale),
// and a correspondence's residual e = R p + t - q has covariance C = R Sigma_p R^T + Sigma_q. It is an inlier when
// e^T C^-1 e < inlier_chi2 (the chi-square quantile of 3 degrees of freedom: 11.34 is 99 %).
// Thread-safety: pure functions. Never throws; degenerate input comes back as a status.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "core/se3.h"

namespace hf {

// One correspondence with its noise (see the header comment).
struct PointPair {
  Eigen::Vector3d current;      // p, current camera frame, metres
  Eigen::Vector3d reference;    // q, reference camera frame, metres
  Eigen::Matrix3d Sigma_current = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d Sigma_reference = Eigen::Matrix3d::Identity();
};

// The covariance of a point measured at `point_m` (camera frame) with lateral sigma `lateral_px` pixels of a camera
// of focal length `focal_px`.
Eigen::Matrix3d depth_point_covariance(const Eigen::Vector3d& point_m, double lateral_px, double focal_px);

// T minimising sum w_i |T p_i - q_i|^2 (Umeyama's closed form without scale). False (T untouched) for fewer than 3
// pairs with positive weight, non-finite input or collinear points (the rotation is then not unique).
bool fit_rigid_weighted(const std::vector<Eigen::Vector3d>& p, const std::vector<Eigen::Vector3d>& q,
                        const std::vector<double>& w, SE3* T);

struct RansacOptions {
  int max_iterations = 1000;       // hypotheses at most
  double confidence = 0.999;       // stop once an all-inlier sample has been drawn with this probability
  double inlier_chi2 = 11.34;      // chi-square(3) at 99 %
  // A sample whose pairwise distances differ between the frames by more than this many sigmas (of the two points'
  // noise) cannot be rigid: rejected before fitting (most random samples with an outlier are caught here).
  double sample_rigidity_sigmas = 5.0;
  double min_sample_spread_m = 0.02;  // sample points closer than this to each other (or to collinear) are skipped
  int refine_iterations = 10;      // Gauss-Newton iterations of the Mahalanobis refinement per inlier round
  int refine_rounds = 3;           // refit -> re-select inliers rounds
  std::uint64_t seed = 1;          // the sampler's seed (results are deterministic)
};

struct RigidEstimate {
  bool ok = false;                 // a hypothesis with at least 3 inliers was found and refined
  SE3 T_ref_cur;
  std::vector<int> inliers;        // indices into the pairs, ascending
  int hypotheses = 0;              // samples fitted
  // At the solution, over the inliers: J^T C^-1 J and J^T C^-1 e with J = d(exp(xi) T p - q)/dxi at xi = 0,
  // xi = (omega, v); cost = sum e^T C^-1 e (chi-square units).
  Matrix6d JtJ = Matrix6d::Zero();
  Vector6d Jtr = Vector6d::Zero();
  double cost = 0.0;
  Vector6d last_step = Vector6d::Zero();  // the refinement's last Gauss-Newton step
};

// RANSAC over 3-point fits, then refinement of the best hypothesis on its inliers (Mahalanobis least squares by
// Gauss-Newton from the weighted closed-form fit), re-selecting the inliers refine_rounds times.
RigidEstimate estimate_rigid_ransac(const std::vector<PointPair>& pairs, const RansacOptions& options = {});

}  // namespace hf
