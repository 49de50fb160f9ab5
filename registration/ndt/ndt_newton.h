// The NDT score and its Newton optimisation, shared by ndt-p2d and ndt-d2d (report eq. 64-66, 74-75; Magnusson
// 2007, chapter 6; Stoyanov et al. 2012).
//
// A term pairs a current-frame point p (a point for p2d, a cell mean for d2d) with a reference Gaussian (mean mu,
// inverse covariance C^-1). At T = T_ref_cur, with x = T p and x' = x - mu, its score is Magnusson's Gaussian
// approximation of the negative log-likelihood, s = d1 exp(-d2/2 x'^T C^-1 x') (d1 < 0) (d1, d2 from the outlier ratio and the cell
// volume, ndt_score_constants), and the sum over the terms is minimised over the left perturbation
// T <- exp(xi) T, xi = (omega, v), by Newton's method with the analytic gradient and Hessian, including the
// exponential map's second derivatives (d^2 x / d omega^2 and d^2 x / d omega dv), the Hessian made positive
// definite by an eigenvalue floor, and a backtracking line search on the score.
//
// Degeneracy: the Newton Hessian is the curvature of a sum of likelihoods, whose in-cell directions are shaped by
// the grid rather than by the surface (a plane's points slide within its cells at almost constant score). The
// information the outcome rules judge (classify_outcome) is therefore sum_k w_k J^T W_k J with w_k the term's
// likelihood weight -d1 d2 exp(-d2/2 q) and W_k the cell's C^-1 restricted to its eigen-directions of sigma below
// cell_m / 6 and within 2x of the thinnest sigma (the others span the cell: the points' spread inside it, or a
// plane's strip cut by the view's edge, not a measurement): on a plane only the normal
// survives, and the two in-plane translations and the rotation about the normal come out degenerate; their
// components are removed from every Newton step (they keep the initial guess, as the driver does).
// Thread-safety: pure functions.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "registration/ndt/ndt_cells.h"
#include "registration/registration.h"

namespace hf {

struct NdtTerm {
  Eigen::Vector3d p;              // current frame
  Eigen::Vector3d mean;           // reference frame
  Eigen::Matrix3d C_inv;          // inverse covariance of x - mean
  Eigen::Matrix3d W_information;  // the constraining part of C_inv (see above)
  double weight = 1.0;            // of the term in the score (ndt-color: the colour kernel, eq. 68-69)
};

// The distribution-to-distribution term of a current cell moved by the rotation R against a reference cell
// (eq. 74: C = R Sigma_cur R^T + Sigma_ref, held fixed within an iteration), standing for the points of the smaller
// cell and constraining the reference cell's directions; false when C is not positive definite.
bool distribution_term(const NdtCell& current, const NdtCell& reference, const Eigen::Matrix3d& R, double cell_m,
                       NdtTerm* term);

// The step without its components along the degenerate eigen-directions of the balanced information (unit_scale
// from balanced_units, directions with eigenvalue <= threshold * the largest).
Vector6d project_out_degenerate(const Vector6d& xi, const Matrix6d& information, const Vector6d& unit_scale,
                                double threshold);

// Magnusson 2007 eq. 6.8: c1 = 10 (1 - outlier_ratio), c2 = outlier_ratio / cell_m^3, d3 = -log c2,
// d1 = -log(c1 + c2) - d3, d2 = -2 log((-log(c1 exp(-1/2) + c2) - d3) / d1).
struct NdtScoreConstants {
  double d1 = -1.0, d2 = 1.0;
};
NdtScoreConstants ndt_score_constants(double outlier_ratio, double cell_m);

// C^-1 restricted to the constraining eigen-directions of Sigma (above; its eigen-decomposition given).
Eigen::Matrix3d constraining_information(const Eigen::Vector3d& eigenvalues, const Eigen::Matrix3d& eigenvectors,
                                         double cell_m);

struct NdtEvaluation {
  double score = 0.0;
  Vector6d gradient = Vector6d::Zero();
  Matrix6d hessian = Matrix6d::Zero();
  Matrix6d information = Matrix6d::Zero();  // sum w J^T W J (see above)
  double cost = 0.0;                         // sum w x'^T C^-1 x' (for the result's final_cost)
  long count = 0;
};
NdtEvaluation evaluate_ndt(const std::vector<NdtTerm>& terms, const SE3& T, const NdtScoreConstants& k,
                           bool derivatives = true);

// One resolution: associates the current data with the reference Gaussians at T (fills terms, clears first).
struct NdtLevel {
  double cell_m = 0.1;
  std::function<void(const SE3& T, std::vector<NdtTerm>* terms)> associate;
};

struct NdtSolveOptions {
  std::vector<int> iterations;     // per level, [0] the finest (the driver's order); 10 where missing
  double outlier_ratio = 0.55;     // PCL's default for NDT
  long min_terms = 64;             // fewer at the finest level: failed
  double rows_possible = 1.0;      // terms the finest level could give (inlier_ratio's denominator)
  Vector6d unit_scale = Vector6d::Ones();  // balanced_units of the current data
};

// Coarse-to-fine Newton over the levels (coarsest first) from T_start (T_initial when null: mrsmap starts from its
// Levenberg-Marquardt estimate), then the outcome by the driver's rules (classify_outcome) with `driver`'s
// thresholds, judged against T_initial. Never throws, never returns a non-finite pose.
RegistrationResult solve_ndt(const std::vector<NdtLevel>& levels, const NdtSolveOptions& options,
                             const GaussNewtonOptions& driver, const SE3& T_initial, const SE3* T_start = nullptr);

}  // namespace hf
