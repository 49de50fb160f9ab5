#include "registration/sparse/rigid_ransac.h"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>

#include "core/kernels/image_kernels.h"

namespace hf {
namespace {

// The information C^-1 of a pair's residual under rotation R, or zero when C is not invertible.
Eigen::Matrix3d residual_information(const PointPair& pair, const Eigen::Matrix3d& R) {
  const Eigen::Matrix3d C = R * pair.Sigma_current * R.transpose() + pair.Sigma_reference;
  Eigen::Matrix3d W;
  bool invertible = false;
  C.computeInverseWithCheck(W, invertible, 1e-30);
  return invertible && W.allFinite() ? W : Eigen::Matrix3d::Zero();
}

double mahalanobis2(const PointPair& pair, const SE3& T, const Eigen::Matrix3d& R) {
  const Eigen::Vector3d e = T * pair.current - pair.reference;
  const double d2 = e.dot(residual_information(pair, R) * e);
  return std::isfinite(d2) ? d2 : std::numeric_limits<double>::infinity();
}

// Inliers of T (ascending) and the sum of their squared Mahalanobis distances.
std::vector<int> select_inliers(const std::vector<PointPair>& pairs, const SE3& T, double chi2, double* cost) {
  const Eigen::Matrix3d R = T.rotation();
  std::vector<int> inliers;
  double sum = 0.0;
  for (size_t i = 0; i < pairs.size(); ++i) {
    const double d2 = mahalanobis2(pairs[i], T, R);
    if (d2 < chi2) {
      inliers.push_back(int(i));
      sum += d2;
    }
  }
  if (cost != nullptr) *cost = sum;
  return inliers;
}

// A sample of three pairs that can be rigid and is spread enough to fix a rotation.
bool sample_usable(const std::vector<PointPair>& pairs, const int idx[3], const RansacOptions& o) {
  for (int a = 0; a < 3; ++a) {
    for (int b = a + 1; b < 3; ++b) {
      const PointPair &A = pairs[size_t(idx[a])], &B = pairs[size_t(idx[b])];
      const double dp = (A.current - B.current).norm(), dq = (A.reference - B.reference).norm();
      if (dp < o.min_sample_spread_m || dq < o.min_sample_spread_m) return false;
      const double var = (A.Sigma_current + B.Sigma_current + A.Sigma_reference + B.Sigma_reference).trace() / 3.0;
      if (std::abs(dp - dq) > o.sample_rigidity_sigmas * std::sqrt(var)) return false;
    }
  }
  const Eigen::Vector3d& a = pairs[size_t(idx[0])].current;
  const Eigen::Vector3d ab = pairs[size_t(idx[1])].current - a, ac = pairs[size_t(idx[2])].current - a;
  return ab.cross(ac).norm() / ac.norm() >= o.min_sample_spread_m;  // distance of b from the line a-c
}

struct Normal6 {
  Matrix6d JtJ = Matrix6d::Zero();
  Vector6d Jtr = Vector6d::Zero();
  double cost = 0.0;
};

// J^T W J, J^T W e and e^T W e over `inliers` at T (left perturbation: d(exp(xi) T p)/dxi = [-[T p]x | I]).
Normal6 accumulate(const std::vector<PointPair>& pairs, const std::vector<int>& inliers, const SE3& T) {
  const Eigen::Matrix3d R = T.rotation();
  Normal6 n;
  for (const int i : inliers) {
    const PointPair& pair = pairs[size_t(i)];
    const Eigen::Vector3d x = T * pair.current;
    const Eigen::Vector3d e = x - pair.reference;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = -skew(x);
    J.rightCols<3>().setIdentity();
    const Eigen::Matrix3d W = residual_information(pair, R);
    const Eigen::Matrix<double, 6, 3> JtW = J.transpose() * W;
    n.JtJ += JtW * J;
    n.Jtr += JtW * e;
    n.cost += e.dot(W * e);
  }
  return n;
}

// Closed-form start (weights 1 / trace C) then Mahalanobis Gauss-Newton on `inliers`. False when not finite.
bool refine(const std::vector<PointPair>& pairs, const std::vector<int>& inliers, const RansacOptions& o, SE3* T,
            Vector6d* last_step) {
  std::vector<Eigen::Vector3d> p, q;
  std::vector<double> w;
  const Eigen::Matrix3d R0 = T->rotation();
  for (const int i : inliers) {
    const PointPair& pair = pairs[size_t(i)];
    p.push_back(pair.current);
    q.push_back(pair.reference);
    w.push_back(1.0 / std::max(1e-12, (R0 * pair.Sigma_current * R0.transpose() + pair.Sigma_reference).trace()));
  }
  SE3 fit = *T;
  if (fit_rigid_weighted(p, q, w, &fit)) *T = fit;
  for (int it = 0; it < o.refine_iterations; ++it) {
    const Normal6 n = accumulate(pairs, inliers, *T);
    const Vector6d xi = n.JtJ.ldlt().solve(-n.Jtr);
    if (!xi.allFinite()) return false;
    *T = SE3::exp(xi) * *T;
    *last_step = xi;
    if (xi.head<3>().norm() < 1e-9 && xi.tail<3>().norm() < 1e-9) break;
  }
  return T->is_finite();
}

}  // namespace

Eigen::Matrix3d depth_point_covariance(const Eigen::Vector3d& point_m, double lateral_px, double focal_px) {
  const double z = point_m.z();
  const Eigen::Vector3d r = point_m.normalized();
  const double sigma_l = z * lateral_px / focal_px;
  const double sigma_z = hf_kinect_axial_sigma_m(float(z));
  const Eigen::Matrix3d rr = r * r.transpose();
  return sigma_l * sigma_l * (Eigen::Matrix3d::Identity() - rr) + sigma_z * sigma_z * rr;
}

bool fit_rigid_weighted(const std::vector<Eigen::Vector3d>& p, const std::vector<Eigen::Vector3d>& q,
                        const std::vector<double>& w, SE3* T) {
  if (p.size() != q.size() || p.size() != w.size() || p.size() < 3) return false;
  double wsum = 0.0;
  Eigen::Vector3d pc = Eigen::Vector3d::Zero(), qc = Eigen::Vector3d::Zero();
  for (size_t i = 0; i < p.size(); ++i) {
    if (!(w[i] > 0.0) || !p[i].allFinite() || !q[i].allFinite() || !std::isfinite(w[i])) continue;
    wsum += w[i];
    pc += w[i] * p[i];
    qc += w[i] * q[i];
  }
  if (!(wsum > 0.0)) return false;
  pc /= wsum;
  qc /= wsum;
  Eigen::Matrix3d H = Eigen::Matrix3d::Zero();  // sum w (p - pc)(q - qc)^T
  for (size_t i = 0; i < p.size(); ++i) {
    if (!(w[i] > 0.0) || !p[i].allFinite() || !q[i].allFinite() || !std::isfinite(w[i])) continue;
    H += w[i] * (p[i] - pc) * (q[i] - qc).transpose();
  }
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Eigen::Vector3d s = svd.singularValues();
  // Collinear points leave the rotation about their line free: rank(H) < 2.
  if (!(s(0) > 0.0) || !(s(1) > 1e-9 * s(0))) return false;
  Eigen::Matrix3d D = Eigen::Matrix3d::Identity();
  D(2, 2) = (svd.matrixV() * svd.matrixU().transpose()).determinant() < 0.0 ? -1.0 : 1.0;
  const Eigen::Matrix3d R = svd.matrixV() * D * svd.matrixU().transpose();
  const Eigen::Vector3d t = qc - R * pc;
  if (!R.allFinite() || !t.allFinite()) return false;
  *T = SE3(R, t);
  return true;
}

RigidEstimate estimate_rigid_ransac(const std::vector<PointPair>& pairs, const RansacOptions& o) {
  RigidEstimate est;
  const int n = int(pairs.size());
  if (n < 3) return est;
  std::mt19937_64 rng(o.seed);
  std::uniform_int_distribution<int> pick(0, n - 1);
  SE3 best_T;
  std::vector<int> best;
  double best_cost = std::numeric_limits<double>::infinity();
  long needed = o.max_iterations;
  for (long draw = 0; draw < std::min<long>(needed, o.max_iterations); ++draw) {
    int idx[3] = {pick(rng), pick(rng), pick(rng)};
    if (idx[0] == idx[1] || idx[0] == idx[2] || idx[1] == idx[2] || !sample_usable(pairs, idx, o)) continue;
    std::vector<Eigen::Vector3d> p, q;
    for (const int i : idx) {
      p.push_back(pairs[size_t(i)].current);
      q.push_back(pairs[size_t(i)].reference);
    }
    SE3 T;
    if (!fit_rigid_weighted(p, q, {1.0, 1.0, 1.0}, &T)) continue;
    ++est.hypotheses;
    double cost = 0.0;
    std::vector<int> inliers = select_inliers(pairs, T, o.inlier_chi2, &cost);
    if (inliers.size() > best.size() || (inliers.size() == best.size() && cost < best_cost)) {
      best = std::move(inliers);
      best_cost = cost;
      best_T = T;
      // Draws for an all-inlier sample with probability `confidence` at the best inlier ratio so far.
      const double w3 = std::pow(double(best.size()) / double(n), 3.0);
      if (w3 >= 1.0) {
        needed = draw + 1;
      } else if (w3 > 0.0) {
        needed = long(std::ceil(std::log(1.0 - o.confidence) / std::log(1.0 - w3)));
      }
    }
  }
  if (best.size() < 3) return est;
  SE3 T = best_T;
  std::vector<int> inliers = best;
  for (int round = 0; round < std::max(1, o.refine_rounds); ++round) {
    if (!refine(pairs, inliers, o, &T, &est.last_step)) return est;
    std::vector<int> again = select_inliers(pairs, T, o.inlier_chi2, nullptr);
    if (again.size() < 3) return est;
    const bool same = again == inliers;
    inliers = std::move(again);
    if (same) break;
  }
  const Normal6 normal = accumulate(pairs, inliers, T);
  if (!normal.JtJ.allFinite() || !normal.Jtr.allFinite() || !std::isfinite(normal.cost)) return est;
  est.ok = true;
  est.T_ref_cur = T;
  est.inliers = std::move(inliers);
  est.JtJ = normal.JtJ;
  est.Jtr = normal.Jtr;
  est.cost = normal.cost;
  return est;
}

}  // namespace hf
