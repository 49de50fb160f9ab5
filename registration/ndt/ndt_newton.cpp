#include "registration/ndt/ndt_newton.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include "registration/gauss_newton.h"

namespace hf {
namespace {

// H made positive definite: eigenvalues floored at 1e-6 of the largest magnitude, then the Newton step.
Vector6d newton_step(const Matrix6d& H, const Vector6d& g) {
  const Eigen::SelfAdjointEigenSolver<Matrix6d> es(0.5 * (H + H.transpose()));
  if (es.info() != Eigen::Success) return Vector6d::Constant(std::nan(""));
  Vector6d lambda = es.eigenvalues();
  const double top = std::max(lambda.cwiseAbs().maxCoeff(), 1e-300);
  for (int i = 0; i < 6; ++i) lambda(i) = std::max(std::abs(lambda(i)), 1e-6 * top);
  return -(es.eigenvectors() * lambda.cwiseInverse().asDiagonal() * es.eigenvectors().transpose()) * g;
}

}  // namespace

Vector6d project_out_degenerate(const Vector6d& xi, const Matrix6d& information, const Vector6d& unit_scale,
                                double threshold) {
  const Matrix6d Hs = unit_scale.asDiagonal() * information * unit_scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Matrix6d> es(Hs);
  if (es.info() != Eigen::Success) return xi;
  const double top = es.eigenvalues()(5);
  Vector6d xs = unit_scale.cwiseInverse().cwiseProduct(xi);  // balanced units
  for (int i = 0; i < 6; ++i) {
    if (!(top > 0.0) || es.eigenvalues()(i) <= threshold * top) {
      const Vector6d u = es.eigenvectors().col(i);
      xs -= u.dot(xs) * u;
    }
  }
  return unit_scale.cwiseProduct(xs);
}

namespace {

// A direction constrains when the cell is about as thin along it as along its thinnest (variance within 4x, sigma
// within 2x): a plane cut by the view's edge into a strip is still a plane.
constexpr double kThinRatio = 4.0;

}  // namespace

bool distribution_term(const NdtCell& current, const NdtCell& reference, const Eigen::Matrix3d& R, double cell_m,
                       NdtTerm* term) {
  const Eigen::Matrix3d C = R * current.Sigma * R.transpose() + reference.Sigma;  // eq. 74
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C);
  if (es.info() != Eigen::Success || !(es.eigenvalues()(0) > 0.0)) return false;
  // A pair of Gaussians stands for the points of the smaller (a full cell beside a sliver of the view's edge is as
  // strong as the sliver); the directions it constrains are the reference cell's.
  *term = {current.mean, reference.mean,
           es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() * es.eigenvectors().transpose(),
           double(std::min(current.count, reference.count)) *
               constraining_information(reference.eigenvalues, reference.eigenvectors, cell_m),
           1.0};
  return true;
}

NdtScoreConstants ndt_score_constants(double outlier_ratio, double cell_m) {
  const double c1 = 10.0 * (1.0 - outlier_ratio);
  const double c2 = outlier_ratio / (cell_m * cell_m * cell_m);
  const double d3 = -std::log(c2);
  NdtScoreConstants k;
  k.d1 = -std::log(c1 + c2) - d3;
  k.d2 = -2.0 * std::log((-std::log(c1 * std::exp(-0.5) + c2) - d3) / k.d1);
  return k;
}

Eigen::Matrix3d constraining_information(const Eigen::Vector3d& eigenvalues, const Eigen::Matrix3d& eigenvectors,
                                         double cell_m) {
  const double spread_var = (cell_m / 6.0) * (cell_m / 6.0);
  Eigen::Matrix3d W = Eigen::Matrix3d::Zero();
  for (int a = 0; a < 3; ++a) {
    if (eigenvalues(a) < spread_var && eigenvalues(a) <= kThinRatio * eigenvalues(0) && eigenvalues(a) > 0.0) {
      W += eigenvectors.col(a) * eigenvectors.col(a).transpose() / eigenvalues(a);
    }
  }
  return W;
}

NdtEvaluation evaluate_ndt(const std::vector<NdtTerm>& terms, const SE3& T, const NdtScoreConstants& k,
                           bool derivatives) {
  NdtEvaluation e;
  const Eigen::Matrix3d R = T.rotation();
  const Eigen::Vector3d t = T.translation();
  for (const NdtTerm& term : terms) {
    const Eigen::Vector3d x = R * term.p + t;
    const Eigen::Vector3d xd = x - term.mean;
    const Eigen::Vector3d y = term.C_inv * xd;
    const double q = xd.dot(y);
    if (!std::isfinite(q)) continue;
    const double E = term.weight * std::exp(-0.5 * k.d2 * q);
    e.score += k.d1 * E;  // d1 < 0: each term is lowest (d1 weight) where x' = 0
    ++e.count;
    if (!derivatives) continue;
    const double w = -k.d1 * k.d2 * E;  // d1 < 0: w > 0
    e.cost += w * q;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = -skew(x);
    J.rightCols<3>().setIdentity();
    const Vector6d Jy = J.transpose() * y;
    // s = d1 E: ds/dxi = -d1 d2 E y^T J = w y^T J; Magnusson eq. 6.12-6.13 with the left perturbation.
    e.gradient += w * Jy;
    Matrix6d S2 = Matrix6d::Zero();  // y^T d^2 x / dxi_a dxi_b
    S2.topLeftCorner<3, 3>() = 0.5 * (y * x.transpose() + x * y.transpose()) - y.dot(x) * Eigen::Matrix3d::Identity();
    S2.topRightCorner<3, 3>() = -0.5 * skew(y);
    S2.bottomLeftCorner<3, 3>() = S2.topRightCorner<3, 3>().transpose();
    e.hessian += w * (J.transpose() * term.C_inv * J + S2 - k.d2 * Jy * Jy.transpose());
    e.information += w * J.transpose() * term.W_information * J;
  }
  return e;
}

RegistrationResult solve_ndt(const std::vector<NdtLevel>& levels, const NdtSolveOptions& options,
                             const GaussNewtonOptions& driver, const SE3& T_initial, const SE3* T_start) {
  RegistrationResult result;
  result.T_ref_cur = T_initial;
  result.iterations_per_level.assign(levels.size(), 0);
  auto fail = [&](RegistrationStatus status, const std::string& message) {
    result.T_ref_cur = T_initial;
    result.status = status;
    result.message = message;
    return result;
  };
  if (levels.empty()) return fail(RegistrationStatus::no_data, "no NDT levels");
  SE3 T = T_start != nullptr && T_start->is_finite() ? *T_start : T_initial;
  std::vector<NdtTerm> terms;
  Vector6d last_step = Vector6d::Zero();
  NdtEvaluation last;
  for (size_t l = 0; l < levels.size(); ++l) {
    const NdtLevel& level = levels[l];
    const NdtScoreConstants k = ndt_score_constants(options.outlier_ratio, level.cell_m);
    const size_t from_finest = levels.size() - 1 - l;
    const int iterations = from_finest < options.iterations.size() ? options.iterations[from_finest] : 10;
    const bool finest = l + 1 == levels.size();
    for (int it = 0; it < iterations; ++it) {
      level.associate(T, &terms);
      if (terms.size() < 6) break;
      const NdtEvaluation e = evaluate_ndt(terms, T, k);
      if (!e.hessian.allFinite() || !e.gradient.allFinite()) return fail(RegistrationStatus::failed, "non-finite NDT derivatives");
      Vector6d xi = project_out_degenerate(newton_step(e.hessian, e.gradient), e.information, options.unit_scale,
                                           driver.degeneracy_threshold);
      if (!xi.allFinite()) return fail(RegistrationStatus::failed, "non-finite NDT step");
      // Backtracking line search on the score of the same association (Armijo with c = 1e-4).
      double alpha = 1.0;
      const double slope = e.gradient.dot(xi);
      for (int ls = 0; ls < 10; ++ls) {
        const double s = evaluate_ndt(terms, SE3::exp(alpha * xi) * T, k, false).score;
        if (s <= e.score + 1e-4 * alpha * std::min(slope, 0.0)) break;
        alpha *= 0.5;
      }
      xi *= alpha;
      T = SE3::exp(xi) * T;
      if (!T.is_finite()) return fail(RegistrationStatus::failed, "the estimate became non-finite");
      ++result.iterations_per_level[l];
      if (finest) last_step = xi;
      if (xi.head<3>().norm() < driver.min_step_rotation_rad && xi.tail<3>().norm() < driver.min_step_translation_m) break;
    }
    if (finest) {
      level.associate(T, &terms);
      last = evaluate_ndt(terms, T, k);
    }
  }
  if (last.count < options.min_terms) {
    return fail(RegistrationStatus::failed,
                "too few NDT correspondences at the finest level (" + std::to_string(last.count) + ")");
  }
  NormalEquations ne;
  ne.JtJ = last.information;
  ne.Jtr = Vector6d::Zero();
  ne.cost = last.cost;
  ne.count = last.count;
  const GaussNewtonStep step = solve_balanced_step(ne, options.unit_scale, driver.degeneracy_threshold);
  if (!step.finite) return fail(RegistrationStatus::failed, "non-finite NDT information");
  classify_outcome(driver, ne, step, options.rows_possible, T_initial, T, last_step, result);
  return result;
}

}  // namespace hf
