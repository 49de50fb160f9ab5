// A keyframe pose graph solved with Ceres (Kuemmerle et al.'s g2o formulation; the loop test after Suenderhauf's
// switchable constraints, done as a post-solve consistency test instead of a switch variable per loop).
//
// Nodes are keyframe poses T_world_node. An edge (from, to) says T_world_to = T_world_from * T_from_to, measured
// with information Lambda (6x6, symmetric positive semi-definite, in the registration's xi = (omega, v) order:
// registration/registration.h). Its residual is the tangent vector of the error transform,
//   r = log(T_from_to^-1 * T_world_from^-1 * T_world_to)          (core/se3.h: exact SE(3) log, rotation first),
// whitened as S r with S^T S = Lambda (S from Lambda's eigen-decomposition, so a singular PSD Lambda constrains only
// the directions it measures), so |S r|^2 is a chi^2 with rank(Lambda) degrees of freedom when the measurement
// noise has covariance Lambda^-1. The cost is 1/2 sum over edges of rho(|S r|^2), rho the identity on odometry
// edges and a Cauchy loss on loop edges. Each pose lives on SE(3) as a unit quaternion (ceres::
// EigenQuaternionManifold) and a translation.
//
// Loop edges (the rule): the solve first runs with rho(s) = c log(1 + s / c) on every loop edge, c =
// loop_loss_chi2 (in chi^2 units: a loop whose whitened squared residual is below c acts almost quadratically, one
// far above it pulls with a force that falls as 1 / |S r|, so a single wrong loop with a high information cannot
// drag the graph far). Then each loop edge whose |S r|^2 at that solution exceeds loop_reject_chi2 is rejected
// (loop_accepted false) and, if any was, the graph is solved again from that solution without them.
//
// Gauge: node 0 is fixed when it is added (set_fixed(0, false) frees it); set_fixed(n) fixes others. A connected
// component of the graph (over its edges) with no fixed node is anchored at its lowest-numbered node's initial
// pose (reported in anchored_components); a node without edges keeps its initial pose.
//
// Failure modes: never throws for bad data and never returns a non-finite pose. optimize() checks its inputs first
// (finite poses; edge indices in range and from != to; finite, symmetric, positive semi-definite, non-zero
// information) and returns PoseGraphStatus::invalid with a message naming the first bad node or edge, and the
// input poses (a non-finite one replaced by the identity). A solver failure or a non-finite solution returns
// failed with the input poses.
// Thread-safety: optimize() is const and may run on another thread while no add_* / set_fixed call runs.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/se3.h"

namespace hf::slam {

enum class PoseGraphEdgeKind { odometry, loop };

struct PoseGraphEdge {
  size_t from = 0, to = 0;
  SE3 T_from_to;                                 // T_world_to = T_world_from * T_from_to
  Matrix6d information = Matrix6d::Identity();  // xi = (omega, v) order; 1 / variance in rad^-2 and m^-2
  PoseGraphEdgeKind kind = PoseGraphEdgeKind::odometry;
};

struct PoseGraphOptions {
  // Cauchy scale c of the loop edges' loss, in chi^2 units (|S r|^2); 0 = no robust loss. Default: chi^2 with 6
  // degrees of freedom at 95 %, 12.59.
  double loop_loss_chi2 = 12.59;
  // A loop edge whose |S r|^2 at the robust solution exceeds this is rejected and the graph solved again without
  // it; <= 0 keeps every loop. Default: chi^2 with 6 degrees of freedom at 99.9 %, 22.46.
  double loop_reject_chi2 = 22.46;
  int max_iterations = 100;       // Levenberg-Marquardt iterations per solve (1 .. 10000)
  double time_budget_ms = 1000.0;  // wall-clock budget of optimize() (all solves together); > 0
  int threads = 1;                // Ceres threads (1 .. 64): tracking owns the other cores
};

enum class PoseGraphStatus {
  converged,       // Ceres reached a convergence tolerance (or there was nothing to optimise)
  max_iterations,  // stopped by max_iterations or time_budget_ms: T_world_node is the best solution so far
  empty,           // no nodes
  degenerate,      // no node is fixed: the gauge is free
  invalid,         // bad input (see message); T_world_node = the input poses
  failed,          // Ceres failed or returned a non-finite solution; T_world_node = the input poses
};
const char* pose_graph_status_name(PoseGraphStatus status);

struct PoseGraphResult {
  PoseGraphStatus status = PoseGraphStatus::empty;
  std::vector<SE3> T_world_node;  // one per node, always finite
  double initial_cost = 0.0;      // 1/2 sum rho(|S r|^2) at the input poses, loop edges robust
  double final_cost = 0.0;        // the same at the solution, over the edges kept (rejected loops left out)
  int iterations = 0;             // Levenberg-Marquardt iterations over all solves
  double ms = 0.0;                // wall-clock time of optimize()
  std::vector<bool> loop_accepted;  // per loop edge, in insertion order
  std::vector<double> loop_chi2;    // per loop edge: |S r|^2 at the robust solution (before any rejection)
  size_t anchored_components = 0;   // components with no fixed node, anchored at their first node
  std::string message;              // why, for every status but converged; notes otherwise
  bool ok() const { return status == PoseGraphStatus::converged || status == PoseGraphStatus::max_iterations; }
};

class PoseGraph {
 public:
  // Returns the new node's index (0, 1, ...). Node 0 starts fixed.
  size_t add_node(const SE3& T_world_node_initial);
  void add_edge(const PoseGraphEdge& edge);
  // Fixes (or frees) a node's pose during optimisation; out-of-range indices are reported by optimize().
  void set_fixed(size_t node, bool fixed = true);
  // Replaces a node's initial pose (e.g. with the previous solution); out-of-range indices are ignored.
  void set_initial(size_t node, const SE3& T_world_node);

  size_t num_nodes() const { return nodes_.size(); }
  size_t num_edges() const { return edges_.size(); }
  const std::vector<SE3>& initial_poses() const { return nodes_; }
  const std::vector<PoseGraphEdge>& edges() const { return edges_; }

  PoseGraphResult optimize(const PoseGraphOptions& options = {}) const;

 private:
  std::vector<SE3> nodes_;
  std::vector<char> fixed_;  // per node
  std::vector<PoseGraphEdge> edges_;
  std::vector<size_t> bad_fixed_;  // set_fixed indices that were out of range (reported by optimize())
};

// The whitened residual S log(T_from_to^-1 T_world_from^-1 T_world_to) of one edge in double (what the solver
// minimises), and its squared norm; false when the information is not symmetric PSD and finite.
bool pose_graph_edge_chi2(const PoseGraphEdge& edge, const SE3& T_world_from, const SE3& T_world_to, double* chi2);

}  // namespace hf::slam
