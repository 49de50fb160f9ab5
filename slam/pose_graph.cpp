#include "slam/pose_graph.h"
#include "core/timing.h"

#include <ceres/autodiff_cost_function.h>
#include <ceres/loss_function.h>
#include <ceres/manifold.h>
#include <ceres/problem.h>
#include <ceres/solver.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>
#include <numeric>
#include <string>

namespace hf::slam {

namespace {

// Below this squared rotation angle the closed forms of log divide small by small; the Taylor terms kept are exact
// to double precision there (next terms ~ theta^4 / 30240), and they keep the Jets' derivatives finite at 0.
constexpr double kSmallAngle2 = 1e-10;

// log of the SE(3) element (q, t), q a unit quaternion as Eigen stores it (x, y, z, w): xi = (omega, v) with
// omega the rotation vector and v = V(omega)^-1 t (core/se3.h), for doubles and Ceres Jets alike.
template <typename T>
void se3_log(const T* q_in, const T* t, T* xi) {
  T q[4] = {q_in[0], q_in[1], q_in[2], q_in[3]};
  if (q[3] < T(0))
    for (T& c : q) c = -c;  // the same rotation with w >= 0, so theta in [0, pi]
  const T n2 = q[0] * q[0] + q[1] * q[1] + q[2] * q[2];
  T omega_per_v, c;  // omega = omega_per_v * vec(q); V^-1 = I - 1/2 W + c W^2
  T theta2;
  if (n2 < T(0.25 * kSmallAngle2)) {
    // theta = 2 atan2(n, w) = (2 / w) n (1 - n^2 / (3 w^2) + ...); c = 1/12 + theta^2 / 720.
    omega_per_v = T(2) / q[3] * (T(1) - n2 / (T(3) * q[3] * q[3]));
    theta2 = omega_per_v * omega_per_v * n2;
    c = T(1.0 / 12.0) + theta2 / T(720);
  } else {
    using std::atan2;
    using std::sqrt;
    const T n = sqrt(n2);
    const T theta = T(2) * atan2(n, q[3]);
    omega_per_v = theta / n;
    theta2 = theta * theta;
    // (t/2) cot(t/2) with cos(t/2) = w and sin(t/2) = n.
    c = (T(1) - T(0.5) * theta * q[3] / n) / theta2;
  }
  const T w[3] = {omega_per_v * q[0], omega_per_v * q[1], omega_per_v * q[2]};
  // W t and W (W t), W = [w]x.
  const T wt[3] = {w[1] * t[2] - w[2] * t[1], w[2] * t[0] - w[0] * t[2], w[0] * t[1] - w[1] * t[0]};
  const T wwt[3] = {w[1] * wt[2] - w[2] * wt[1], w[2] * wt[0] - w[0] * wt[2], w[0] * wt[1] - w[1] * wt[0]};
  for (int i = 0; i < 3; ++i) {
    xi[i] = w[i];
    xi[3 + i] = t[i] - T(0.5) * wt[i] + c * wwt[i];
  }
}

// The whitened edge residual S log(T_from_to^-1 T_world_from^-1 T_world_to) (the header's r).
struct EdgeResidual {
  EdgeResidual(const SE3& T_from_to, const Matrix6d& S) : S_(S) {
    const SE3 T_to_from = T_from_to.inverse();
    q_to_from_ = T_to_from.quaternion();
    t_to_from_ = T_to_from.translation();
  }

  template <typename T>
  bool operator()(const T* q_wf, const T* t_wf, const T* q_wt, const T* t_wt, T* residual) const {
    using Quat = Eigen::Quaternion<T>;
    using Vec3 = Eigen::Matrix<T, 3, 1>;
    const Eigen::Map<const Quat> Q_wf(q_wf), Q_wt(q_wt);
    const Eigen::Map<const Vec3> P_wf(t_wf), P_wt(t_wt);
    // T_from_world * T_world_to, then T_to_from(measured) * that.
    const Quat q_fw = Q_wf.conjugate();
    const Quat q_rel = q_fw * Q_wt;
    const Vec3 t_rel = q_fw * (P_wt - P_wf);
    const Quat q_m = q_to_from_.template cast<T>();
    const Quat q_err = q_m * q_rel;
    const Vec3 t_err = q_m * t_rel + t_to_from_.template cast<T>();
    T xi[6];
    se3_log(q_err.coeffs().data(), t_err.data(), xi);
    for (int i = 0; i < 6; ++i) {
      residual[i] = T(0);
      for (int j = 0; j < 6; ++j) residual[i] += T(S_(i, j)) * xi[j];
    }
    return true;
  }

  Matrix6d S_;
  Eigen::Quaterniond q_to_from_;
  Eigen::Vector3d t_to_from_;
};

// S with S^T S = information, from its eigen-decomposition; false when the information is not finite, symmetric
// and positive semi-definite with a positive largest eigenvalue (relative tolerances 1e-9).
bool whitening(const Matrix6d& information, Matrix6d* S, std::string* why) {
  if (!information.allFinite()) {
    *why = "information is not finite";
    return false;
  }
  const double scale = information.cwiseAbs().maxCoeff();
  if (!(scale > 0.0)) {
    *why = "information is zero";
    return false;
  }
  if ((information - information.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale) {
    *why = "information is not symmetric";
    return false;
  }
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(0.5 * (information + information.transpose()));
  if (eig.info() != Eigen::Success) {
    *why = "information has no eigen-decomposition";
    return false;
  }
  const Vector6d lambda = eig.eigenvalues();
  if (lambda.minCoeff() < -1e-9 * lambda.maxCoeff()) {
    *why = "information is not positive semi-definite (eigenvalue " + std::to_string(lambda.minCoeff()) + ")";
    return false;
  }
  *S = lambda.cwiseMax(0.0).cwiseSqrt().asDiagonal() * eig.eigenvectors().transpose();
  return true;
}

double robust(double chi2, const PoseGraphEdge& edge, const PoseGraphOptions& options) {
  if (edge.kind != PoseGraphEdgeKind::loop || options.loop_loss_chi2 <= 0.0) return chi2;
  return options.loop_loss_chi2 * std::log1p(chi2 / options.loop_loss_chi2);
}

// Levenberg-Marquardt iterations of a solve (Ceres' list starts with the initial point).
int iterations_of(const ceres::Solver::Summary& summary) { return std::max(0, int(summary.iterations.size()) - 1); }

// The first problem with the graph's inputs, or "" when they are usable.
std::string check_inputs(const std::vector<SE3>& nodes, const std::vector<PoseGraphEdge>& edges,
                         const std::vector<size_t>& bad_fixed, const PoseGraphOptions& options,
                         std::vector<Matrix6d>* S) {
  if (!(options.max_iterations >= 1 && options.max_iterations <= 10000))
    return "options: max_iterations must be in 1 .. 10000";
  if (!(options.time_budget_ms > 0.0) || !std::isfinite(options.time_budget_ms))
    return "options: time_budget_ms must be positive and finite";
  if (!(options.threads >= 1 && options.threads <= 64)) return "options: threads must be in 1 .. 64";
  if (!std::isfinite(options.loop_loss_chi2) || !std::isfinite(options.loop_reject_chi2))
    return "options: loop_loss_chi2 and loop_reject_chi2 must be finite";
  if (!bad_fixed.empty())
    return "set_fixed(" + std::to_string(bad_fixed.front()) + "): no such node (" + std::to_string(nodes.size()) +
           " nodes)";
  for (size_t i = 0; i < nodes.size(); ++i)
    if (!nodes[i].is_finite()) return "node " + std::to_string(i) + ": initial pose is not finite";
  S->resize(edges.size());
  for (size_t k = 0; k < edges.size(); ++k) {
    const PoseGraphEdge& e = edges[k];
    const std::string name = "edge " + std::to_string(k) + " (" + std::to_string(e.from) + " -> " +
                             std::to_string(e.to) + ")";
    if (e.from >= nodes.size() || e.to >= nodes.size())
      return name + ": node index out of range (" + std::to_string(nodes.size()) + " nodes)";
    if (e.from == e.to) return name + ": an edge must join two different nodes";
    if (!e.T_from_to.is_finite()) return name + ": T_from_to is not finite";
    std::string why;
    if (!whitening(e.information, &(*S)[k], &why)) return name + ": " + why;
  }
  return "";
}

// Union-find root with path halving.
size_t root(std::vector<size_t>& parent, size_t i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Per node: whether its pose is held constant (fixed, or the anchor of a component without a fixed node).
std::vector<char> constant_nodes(const std::vector<char>& fixed, const std::vector<PoseGraphEdge>& edges,
                                 size_t* anchored) {
  const size_t n = fixed.size();
  std::vector<size_t> parent(n);
  std::iota(parent.begin(), parent.end(), size_t(0));
  std::vector<char> has_edge(n, 0);
  for (const PoseGraphEdge& e : edges) {
    parent[root(parent, e.from)] = root(parent, e.to);
    has_edge[e.from] = has_edge[e.to] = 1;
  }
  std::vector<char> component_fixed(n, 0);
  for (size_t i = 0; i < n; ++i)
    if (fixed[i]) component_fixed[root(parent, i)] = 1;
  std::vector<char> constant = fixed;
  *anchored = 0;
  for (size_t i = 0; i < n; ++i) {  // ascending: the first node of a free component anchors it
    const size_t r = root(parent, i);
    if (has_edge[i] && !component_fixed[r]) {
      component_fixed[r] = 1;
      constant[i] = 1;
      ++*anchored;
    }
  }
  return constant;
}

// One Levenberg-Marquardt solve over the edges with use[k], from and into (q, t). Returns Ceres' summary.
ceres::Solver::Summary solve(const std::vector<PoseGraphEdge>& edges, const std::vector<Matrix6d>& S,
                             const std::vector<char>& use, const std::vector<char>& constant,
                             const PoseGraphOptions& options, double budget_s, std::vector<Eigen::Quaterniond>& q,
                             std::vector<Eigen::Vector3d>& t) {
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion_manifold;
  std::unique_ptr<ceres::LossFunction> loop_loss;
  if (options.loop_loss_chi2 > 0.0) loop_loss = std::make_unique<ceres::CauchyLoss>(std::sqrt(options.loop_loss_chi2));
  std::vector<char> added(q.size(), 0);
  auto add_node = [&](size_t i) {
    if (added[i]) return;
    added[i] = 1;
    problem.AddParameterBlock(q[i].coeffs().data(), 4, &quaternion_manifold);
    problem.AddParameterBlock(t[i].data(), 3);
    if (constant[i]) {
      problem.SetParameterBlockConstant(q[i].coeffs().data());
      problem.SetParameterBlockConstant(t[i].data());
    }
  };
  for (size_t k = 0; k < edges.size(); ++k) {
    if (!use[k]) continue;
    const PoseGraphEdge& e = edges[k];
    add_node(e.from);
    add_node(e.to);
    auto* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 6, 4, 3, 4, 3>(new EdgeResidual(e.T_from_to, S[k]));
    problem.AddResidualBlock(cost, e.kind == PoseGraphEdgeKind::loop ? loop_loss.get() : nullptr,
                             q[e.from].coeffs().data(), t[e.from].data(), q[e.to].coeffs().data(), t[e.to].data());
  }
  ceres::Solver::Options solver_options;
  solver_options.linear_solver_type =
      ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::SUITE_SPARSE) ||
              ceres::IsSparseLinearAlgebraLibraryTypeAvailable(ceres::EIGEN_SPARSE)
          ? ceres::SPARSE_NORMAL_CHOLESKY
          : ceres::DENSE_QR;
  solver_options.max_num_iterations = options.max_iterations;
  solver_options.max_solver_time_in_seconds = std::max(budget_s, 1e-6);
  solver_options.num_threads = options.threads;
  solver_options.logging_type = ceres::SILENT;
  solver_options.minimizer_progress_to_stdout = false;
  ceres::Solver::Summary summary;
  ceres::Solve(solver_options, &problem, &summary);
  return summary;
}

}  // namespace

const char* pose_graph_status_name(PoseGraphStatus status) {
  switch (status) {
    case PoseGraphStatus::converged: return "converged";
    case PoseGraphStatus::max_iterations: return "max_iterations";
    case PoseGraphStatus::empty: return "empty";
    case PoseGraphStatus::degenerate: return "degenerate";
    case PoseGraphStatus::invalid: return "invalid";
    case PoseGraphStatus::failed: return "failed";
  }
  return "unknown";
}

size_t PoseGraph::add_node(const SE3& T_world_node_initial) {
  nodes_.push_back(T_world_node_initial);
  fixed_.push_back(nodes_.size() == 1 ? 1 : 0);
  return nodes_.size() - 1;
}

void PoseGraph::add_edge(const PoseGraphEdge& edge) { edges_.push_back(edge); }

void PoseGraph::set_fixed(size_t node, bool fixed) {
  if (node < fixed_.size())
    fixed_[node] = fixed ? 1 : 0;
  else
    bad_fixed_.push_back(node);
}

void PoseGraph::set_initial(size_t node, const SE3& T_world_node) {
  if (node < nodes_.size()) nodes_[node] = T_world_node;
}

bool pose_graph_edge_chi2(const PoseGraphEdge& edge, const SE3& T_world_from, const SE3& T_world_to, double* chi2) {
  Matrix6d S;
  std::string why;
  if (!whitening(edge.information, &S, &why)) return false;
  const EdgeResidual residual(edge.T_from_to, S);
  Vector6d r;
  residual(T_world_from.quaternion().coeffs().data(), T_world_from.translation().data(),
           T_world_to.quaternion().coeffs().data(), T_world_to.translation().data(), r.data());
  *chi2 = r.squaredNorm();
  return std::isfinite(*chi2);
}

PoseGraphResult PoseGraph::optimize(const PoseGraphOptions& options) const {
  const auto t0 = std::chrono::steady_clock::now();
  PoseGraphResult result;
  result.T_world_node = nodes_;
  for (SE3& T : result.T_world_node)
    if (!T.is_finite()) T = SE3::identity();
  size_t loops = 0;
  for (const PoseGraphEdge& e : edges_) loops += e.kind == PoseGraphEdgeKind::loop ? 1 : 0;
  result.loop_accepted.assign(loops, true);
  result.loop_chi2.assign(loops, 0.0);
  auto finish = [&](PoseGraphStatus status, std::string message) {
    result.status = status;
    result.message = std::move(message);
    result.ms = ms_since(t0);
    return result;
  };

  std::vector<Matrix6d> S;
  const std::string bad = check_inputs(nodes_, edges_, bad_fixed_, options, &S);
  if (!bad.empty()) return finish(PoseGraphStatus::invalid, bad);
  if (nodes_.empty()) return finish(PoseGraphStatus::empty, "the graph has no nodes");
  if (std::none_of(fixed_.begin(), fixed_.end(), [](char f) { return f != 0; }))
    return finish(PoseGraphStatus::degenerate, "no node is fixed: the gauge is free");

  const std::vector<char> constant = constant_nodes(fixed_, edges_, &result.anchored_components);
  std::vector<Eigen::Quaterniond> q(nodes_.size());
  std::vector<Eigen::Vector3d> t(nodes_.size());
  for (size_t i = 0; i < nodes_.size(); ++i) {
    q[i] = nodes_[i].quaternion();
    t[i] = nodes_[i].translation();
  }
  // 1/2 sum rho(|S r|^2) over the edges with use[k], and each loop's |S r|^2, at (q, t).
  auto cost = [&](const std::vector<char>& use, std::vector<double>* loop_chi2) {
    double sum = 0.0;
    size_t loop = 0;
    for (size_t k = 0; k < edges_.size(); ++k) {
      const PoseGraphEdge& e = edges_[k];
      Vector6d r;
      EdgeResidual(e.T_from_to, S[k])(q[e.from].coeffs().data(), t[e.from].data(), q[e.to].coeffs().data(),
                                      t[e.to].data(), r.data());
      const double chi2 = r.squaredNorm();
      if (use[k]) sum += robust(chi2, e, options);
      if (e.kind == PoseGraphEdgeKind::loop) {
        if (loop_chi2) (*loop_chi2)[loop] = chi2;
        ++loop;
      }
    }
    return 0.5 * sum;
  };
  std::vector<char> use(edges_.size(), 1);
  result.initial_cost = cost(use, nullptr);
  if (edges_.empty()) {
    result.final_cost = 0.0;
    return finish(PoseGraphStatus::converged, "no edges: nothing to optimise");
  }

  const double budget_s = 1e-3 * options.time_budget_ms;
  std::string notes;
  if (result.anchored_components > 0)
    notes = std::to_string(result.anchored_components) +
            " component(s) without a fixed node anchored at their first node's initial pose";
  ceres::Solver::Summary summary = solve(edges_, S, use, constant, options, budget_s, q, t);
  result.iterations = iterations_of(summary);
  cost(use, &result.loop_chi2);

  // The consistency test: loops the robust solution could not satisfy are dropped and the graph solved again.
  size_t rejected = 0;
  if (options.loop_reject_chi2 > 0.0) {
    size_t loop = 0;
    for (size_t k = 0; k < edges_.size(); ++k) {
      if (edges_[k].kind != PoseGraphEdgeKind::loop) continue;
      if (!(result.loop_chi2[loop] <= options.loop_reject_chi2)) {
        use[k] = 0;
        result.loop_accepted[loop] = false;
        ++rejected;
      }
      ++loop;
    }
  }
  if (rejected > 0 && summary.termination_type != ceres::FAILURE) {
    const double left_s = budget_s - 1e-3 * ms_since(t0);
    if (left_s > 0.0) {
      summary = solve(edges_, S, use, constant, options, left_s, q, t);
      result.iterations += iterations_of(summary);
    } else {
      summary.termination_type = ceres::NO_CONVERGENCE;
    }
    notes += std::string(notes.empty() ? "" : "; ") + std::to_string(rejected) + " loop edge(s) rejected";
  }

  bool finite = true;
  for (size_t i = 0; i < nodes_.size() && finite; ++i) finite = q[i].coeffs().allFinite() && t[i].allFinite();
  if (summary.termination_type == ceres::FAILURE || summary.termination_type == ceres::USER_FAILURE || !finite) {
    result.loop_accepted.assign(loops, true);
    return finish(PoseGraphStatus::failed,
                  finite ? "Ceres failed: " + summary.message : "the solution is not finite");
  }
  for (size_t i = 0; i < nodes_.size(); ++i) result.T_world_node[i] = SE3(q[i], t[i]);
  result.final_cost = cost(use, nullptr);
  if (summary.termination_type == ceres::NO_CONVERGENCE)
    return finish(PoseGraphStatus::max_iterations,
                  "stopped by max_iterations or time_budget_ms" + (notes.empty() ? "" : "; " + notes));
  return finish(PoseGraphStatus::converged, notes);
}

}  // namespace hf::slam
