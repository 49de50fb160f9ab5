// The keyframe pose graph (slam/pose_graph.h) on graphs with exact ground truth: a loop of poses whose odometry is
// the truth plus seeded Gaussian noise of known covariance, with and without a false loop, and every kind of bad or
// degenerate input.
#include "slam/pose_graph.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Dense>

namespace hf::slam {
namespace {

constexpr double kSigmaRotRad = 0.01;  // odometry noise per edge, each rotation axis
constexpr double kSigmaTransM = 0.01;  // and each translation axis

Matrix6d information_of(double sigma_rot, double sigma_trans) {
  Vector6d d;
  d << Eigen::Vector3d::Constant(1.0 / (sigma_rot * sigma_rot)), Eigen::Vector3d::Constant(1.0 / (sigma_trans * sigma_trans));
  return d.asDiagonal();
}

// Node i of n on a circle of radius 2 m with a vertical wobble, looking along its tangent with some roll.
SE3 circle_pose(int i, int n) {
  const double a = 2.0 * M_PI * i / n;
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.2 * std::sin(3.0 * a), Eigen::Vector3d::UnitX()))
                                .toRotationMatrix();
  return SE3(R, Eigen::Vector3d(2.0 * std::cos(a), 2.0 * std::sin(a), 0.2 * std::sin(2.0 * a)));
}

Vector6d gaussian(std::mt19937& rng, double sigma_rot, double sigma_trans) {
  std::normal_distribution<double> N(0.0, 1.0);
  Vector6d xi;
  for (int k = 0; k < 3; ++k) xi[k] = sigma_rot * N(rng);
  for (int k = 3; k < 6; ++k) xi[k] = sigma_trans * N(rng);
  return xi;
}

// A measurement of T_from_to with noise exp(xi) on the right: its residual at the truth is -xi (covariance the
// inverse of the edge's information).
PoseGraphEdge noisy_edge(const SE3& T_world_from, const SE3& T_world_to, size_t from, size_t to, std::mt19937& rng,
                         PoseGraphEdgeKind kind) {
  PoseGraphEdge e;
  e.from = from;
  e.to = to;
  e.T_from_to = T_world_from.inverse() * T_world_to * SE3::exp(gaussian(rng, kSigmaRotRad, kSigmaTransM));
  e.information = information_of(kSigmaRotRad, kSigmaTransM);
  e.kind = kind;
  return e;
}

// The 40-node loop: odometry i -> i + 1 and one loop edge 39 -> 0, all with the same noise; initial poses dead
// reckoned from node 0 (at its true pose, fixed).
struct LoopGraph {
  static constexpr int n = 40;
  std::vector<SE3> truth;
  std::vector<SE3> dead_reckoned;
  PoseGraph graph;
  explicit LoopGraph(unsigned seed) {
    std::mt19937 rng(seed);
    for (int i = 0; i < n; ++i) truth.push_back(circle_pose(i, n));
    std::vector<PoseGraphEdge> odometry;
    for (int i = 0; i + 1 < n; ++i)
      odometry.push_back(noisy_edge(truth[i], truth[i + 1], i, i + 1, rng, PoseGraphEdgeKind::odometry));
    dead_reckoned.push_back(truth[0]);
    for (const PoseGraphEdge& e : odometry) dead_reckoned.push_back(dead_reckoned.back() * e.T_from_to);
    for (const SE3& T : dead_reckoned) graph.add_node(T);
    for (const PoseGraphEdge& e : odometry) graph.add_edge(e);
    graph.add_edge(noisy_edge(truth[n - 1], truth[0], n - 1, 0, rng, PoseGraphEdgeKind::loop));
  }
};

Matrix6d adjoint(const SE3& T) {  // xi = (omega, v): Ad = [[R, 0], [t^ R, R]]
  Matrix6d A = Matrix6d::Zero();
  const Eigen::Matrix3d R = T.rotation();
  A.topLeftCorner<3, 3>() = R;
  A.bottomRightCorner<3, 3>() = R;
  A.bottomLeftCorner<3, 3>() = skew(T.translation()) * R;
  return A;
}

// The information of the estimate's error delta_i = log(T_true_i^-1 T_est_i) (nodes 1..n-1; node 0 fixed), from
// the edges linearised at the truth: r_k ~ delta_to - Ad(T_from_to^-1) delta_from - xi_k, so the estimate of this
// linear-Gaussian problem errs by N(0, H^-1), H = sum J^T Lambda J. delta^T H delta is then chi^2 with 6 (n - 1)
// degrees of freedom, and each node's 6x6 block of H^-1 its own covariance.
Eigen::MatrixXd error_information(const LoopGraph& g) {
  const int m = 6 * (g.n - 1);
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(m, m);
  for (const PoseGraphEdge& e : g.graph.edges()) {
    const SE3 T_from_to = g.truth[e.from].inverse() * g.truth[e.to];
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(6, m + 6);  // with node 0's columns, dropped below
    J.block<6, 6>(0, 6 * e.to) = Matrix6d::Identity();
    J.block<6, 6>(0, 6 * e.from) = -adjoint(T_from_to.inverse());
    const Eigen::MatrixXd Jv = J.rightCols(m);
    H += Jv.transpose() * e.information * Jv;
  }
  return H;
}

Eigen::VectorXd errors(const LoopGraph& g, const std::vector<SE3>& estimate) {
  Eigen::VectorXd delta(6 * (g.n - 1));
  for (int i = 1; i < g.n; ++i) delta.segment<6>(6 * (i - 1)) = (g.truth[i].inverse() * estimate[i]).log();
  return delta;
}

double rms_translation_m(const LoopGraph& g, const std::vector<SE3>& estimate) {
  double sum = 0.0;
  for (int i = 0; i < g.n; ++i) sum += (estimate[i].translation() - g.truth[i].translation()).squaredNorm();
  return std::sqrt(sum / g.n);
}

// Chi-square quantiles used below (6 (n - 1) = 234 degrees of freedom: mean 234, sd sqrt(2 * 234) = 21.6).
constexpr double kChi2Dof6Quantile9999 = 27.86;
const double kChi2Dof234Bound = 234.0 + 5.0 * std::sqrt(2.0 * 234.0);

bool all_finite(const PoseGraphResult& r) {
  for (const SE3& T : r.T_world_node)
    if (!T.is_finite()) return false;
  return std::isfinite(r.initial_cost) && std::isfinite(r.final_cost);
}

// The solver's residual is the exact SE(3) log of core/se3.h: with identity information, chi^2 = |log|^2, from
// tiny rotations (the Taylor branch) to rotations near pi.
TEST(PoseGraph, EdgeResidualIsTheSe3Log) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  for (const double angle : {0.0, 1e-9, 1e-6, 1e-3, 0.5, 2.0, 3.1, M_PI - 1e-6}) {
    for (int trial = 0; trial < 10; ++trial) {
      const Eigen::Vector3d axis = Eigen::Vector3d(U(rng), U(rng), U(rng)).normalized();
      const SE3 error(Eigen::Matrix3d(Eigen::AngleAxisd(angle, axis)), Eigen::Vector3d(U(rng), U(rng), U(rng)));
      const SE3 T_world_from(Eigen::Matrix3d(Eigen::AngleAxisd(U(rng) * 3.0, axis.unitOrthogonal())),
                             Eigen::Vector3d(U(rng), U(rng), U(rng)));
      PoseGraphEdge e;
      e.T_from_to = SE3(Eigen::Matrix3d(Eigen::AngleAxisd(U(rng), axis)), Eigen::Vector3d(U(rng), 0.0, 0.0));
      const SE3 T_world_to = T_world_from * e.T_from_to * error;
      double chi2 = -1.0;
      ASSERT_TRUE(pose_graph_edge_chi2(e, T_world_from, T_world_to, &chi2));
      const double expected = error.log().squaredNorm();
      EXPECT_NEAR(chi2, expected, 1e-9 * (1.0 + expected)) << "angle " << angle;
    }
  }
}

// Odometry equal to the truth, initial poses perturbed by ~10 cm and ~6 degrees: the solution is the truth.
TEST(PoseGraph, ExactOdometryRecoversTheTruth) {
  const int n = 20;
  std::mt19937 rng(5);
  PoseGraph graph;
  std::vector<SE3> truth;
  for (int i = 0; i < n; ++i) truth.push_back(circle_pose(i, n));
  for (int i = 0; i < n; ++i) graph.add_node(i == 0 ? truth[0] : truth[i] * SE3::exp(gaussian(rng, 0.1, 0.1)));
  for (int i = 0; i < n; ++i) {
    PoseGraphEdge e;
    e.from = size_t(i);
    e.to = size_t((i + 1) % n);
    e.T_from_to = truth[e.from].inverse() * truth[e.to];
    e.kind = i + 1 == n ? PoseGraphEdgeKind::loop : PoseGraphEdgeKind::odometry;
    graph.add_edge(e);
  }
  const PoseGraphResult r = graph.optimize();
  ASSERT_EQ(r.status, PoseGraphStatus::converged) << r.message;
  EXPECT_GT(r.initial_cost, 1.0);
  EXPECT_LT(r.final_cost, 1e-12);
  EXPECT_EQ(r.loop_accepted, std::vector<bool>{true});
  for (int i = 0; i < n; ++i) EXPECT_LT((truth[i].inverse() * r.T_world_node[i]).log().norm(), 1e-6) << i;
}

// (a) The noisy loop: the solution's error is that of the linear-Gaussian estimate (chi^2 bounds from the noise
// covariance, whole trajectory and per node) and far below dead reckoning's.
TEST(PoseGraph, NoisyLoopRecoversTheTruthWithinTheNoise) {
  for (const unsigned seed : {1u, 2u, 3u}) {
    SCOPED_TRACE(seed);
    const LoopGraph g(seed);
    const PoseGraphResult r = g.graph.optimize();
    ASSERT_EQ(r.status, PoseGraphStatus::converged) << r.message;
    ASSERT_TRUE(all_finite(r));
    EXPECT_EQ(r.loop_accepted, std::vector<bool>{true});
    EXPECT_LT(r.final_cost, r.initial_cost);
    const Eigen::MatrixXd H = error_information(g);
    const Eigen::MatrixXd cov = H.inverse();
    const Eigen::VectorXd delta = errors(g, r.T_world_node);
    EXPECT_LT(delta.dot(H * delta), kChi2Dof234Bound);
    for (int i = 1; i < g.n; ++i) {
      const Vector6d d = delta.segment<6>(6 * (i - 1));
      const Matrix6d C = cov.block<6, 6>(6 * (i - 1), 6 * (i - 1));
      EXPECT_LT(d.dot(C.ldlt().solve(d)), kChi2Dof6Quantile9999) << "node " << i;
    }
    // In metres: the RMS translation error against its expectation sqrt(mean tr(Sigma_v)) (the translation
    // block of each node's covariance; world translation error = R_i v_i to first order), and below dead
    // reckoning's, the random walk of 39 edges that the loop does not bound.
    double expected_m2 = 0.0;
    for (int i = 1; i < g.n; ++i) expected_m2 += cov.block<3, 3>(6 * (i - 1) + 3, 6 * (i - 1) + 3).trace();
    const double expected_m = std::sqrt(expected_m2 / g.n);
    const double dead_m = rms_translation_m(g, g.dead_reckoned), solved_m = rms_translation_m(g, r.T_world_node);
    EXPECT_LT(solved_m, 2.0 * expected_m) << "expected " << expected_m << " m";
    EXPECT_LT(solved_m, dead_m) << "dead reckoned " << dead_m << " m, solved " << solved_m << " m";
    const Eigen::VectorXd dead = errors(g, g.dead_reckoned);
    EXPECT_GT(dead.dot(H * dead), delta.dot(H * delta));
  }
}

// (b) The same loop plus a false loop edge (10 -> 30 claims the two are 3 m and 90 degrees from where they are,
// with 100x the odometry's information): it is rejected and the solution is that of (a); with the robust loss
// alone (no rejection) it moves the graph little; with neither, it wrecks it.
TEST(PoseGraph, FalseLoopIsRejectedAndDoesNotWreckTheGraph) {
  const LoopGraph clean(1);
  const PoseGraphResult reference = clean.graph.optimize();
  ASSERT_EQ(reference.status, PoseGraphStatus::converged);
  LoopGraph g(1);
  PoseGraphEdge wrong;
  wrong.from = 10;
  wrong.to = 30;
  Vector6d xi;
  xi << 0.0, M_PI / 2, 0.0, 3.0, 0.0, 0.0;
  wrong.T_from_to = g.truth[10].inverse() * g.truth[30] * SE3::exp(xi);
  wrong.information = 100.0 * information_of(kSigmaRotRad, kSigmaTransM);
  wrong.kind = PoseGraphEdgeKind::loop;
  g.graph.add_edge(wrong);

  const PoseGraphResult r = g.graph.optimize();
  ASSERT_TRUE(r.ok()) << r.message;
  ASSERT_TRUE(all_finite(r));
  EXPECT_EQ(r.loop_accepted, (std::vector<bool>{true, false}));
  EXPECT_LT(r.loop_chi2[0], PoseGraphOptions{}.loop_reject_chi2);
  EXPECT_GT(r.loop_chi2[1], 1e4);
  // Both solves stop at Ceres' relative function tolerance (1e-6): the same optimum to well under the noise.
  double max_diff_m = 0.0;
  for (int i = 0; i < g.n; ++i)
    max_diff_m = std::max(max_diff_m, (r.T_world_node[i].translation() - reference.T_world_node[i].translation()).norm());
  EXPECT_LT(max_diff_m, 0.1 * kSigmaTransM);

  // Robust loss alone: the false loop pulls with a force of at most ~2 c / |r| and the error stays within the
  // noise of (a), a small multiple of it.
  PoseGraphOptions robust_only;
  robust_only.loop_reject_chi2 = 0.0;
  const PoseGraphResult robust = g.graph.optimize(robust_only);
  ASSERT_TRUE(robust.ok()) << robust.message;
  EXPECT_EQ(robust.loop_accepted, (std::vector<bool>{true, true}));
  const double reference_m = rms_translation_m(g, reference.T_world_node);
  EXPECT_LT(rms_translation_m(g, robust.T_world_node), reference_m + 2.0 * kSigmaTransM);

  // Neither: least squares follows the false loop (the test above can tell).
  PoseGraphOptions plain;
  plain.loop_reject_chi2 = 0.0;
  plain.loop_loss_chi2 = 0.0;
  const PoseGraphResult wrecked = g.graph.optimize(plain);
  ASSERT_TRUE(wrecked.ok()) << wrecked.message;
  EXPECT_GT(rms_translation_m(g, wrecked.T_world_node), 10.0 * reference_m);
}

// (c) Degenerate and bad input: a status, finite poses, no throw.
TEST(PoseGraph, EmptyAndTrivialGraphs) {
  PoseGraph empty;
  const PoseGraphResult r0 = empty.optimize();
  EXPECT_EQ(r0.status, PoseGraphStatus::empty);
  EXPECT_TRUE(r0.T_world_node.empty());

  PoseGraph single;
  single.add_node(circle_pose(3, 10));
  const PoseGraphResult r1 = single.optimize();
  EXPECT_EQ(r1.status, PoseGraphStatus::converged) << r1.message;
  ASSERT_EQ(r1.T_world_node.size(), 1u);
  EXPECT_LT((r1.T_world_node[0].inverse() * circle_pose(3, 10)).log().norm(), 1e-12);

  // Gauge freed and nothing fixed.
  PoseGraph free_gauge;
  free_gauge.add_node(SE3());
  free_gauge.add_node(SE3());
  free_gauge.add_edge(PoseGraphEdge{0, 1, SE3::exp(Vector6d::Constant(0.1)), Matrix6d::Identity(),
                                    PoseGraphEdgeKind::odometry});
  free_gauge.set_fixed(0, false);
  const PoseGraphResult r2 = free_gauge.optimize();
  EXPECT_EQ(r2.status, PoseGraphStatus::degenerate);
  EXPECT_EQ(r2.T_world_node.size(), 2u);
}

// Two components and an isolated node: the component without a fixed node is anchored at its first node, the
// isolated node keeps its pose, both components are solved.
TEST(PoseGraph, DisconnectedComponentsAreAnchored) {
  PoseGraph graph;
  const SE3 step = SE3::exp((Vector6d() << 0.0, 0.0, 0.1, 0.5, 0.0, 0.0).finished());
  const SE3 far(Eigen::Quaterniond::Identity(), Eigen::Vector3d(10, 0, 0));
  for (int i = 0; i < 3; ++i) graph.add_node(SE3());        // 0-2, the fixed component
  for (int i = 0; i < 3; ++i) graph.add_node(far);          // 3-5, no fixed node
  graph.add_node(SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0, 7, 0)));  // 6, isolated
  for (size_t i : {size_t(0), size_t(1), size_t(3), size_t(4)})
    graph.add_edge(PoseGraphEdge{i, i + 1, step, Matrix6d::Identity(), PoseGraphEdgeKind::odometry});
  const PoseGraphResult r = graph.optimize();
  ASSERT_EQ(r.status, PoseGraphStatus::converged) << r.message;
  ASSERT_TRUE(all_finite(r));
  EXPECT_EQ(r.anchored_components, 1u);
  EXPECT_LT((r.T_world_node[2].inverse() * (step * step)).log().norm(), 1e-6);
  EXPECT_LT((r.T_world_node[3].inverse() * far).log().norm(), 1e-12);
  EXPECT_LT((r.T_world_node[5].inverse() * (far * step * step)).log().norm(), 1e-6);
  EXPECT_EQ(r.T_world_node[6].translation(), Eigen::Vector3d(0, 7, 0));
}

TEST(PoseGraph, BadInputGivesInvalidAndFinitePoses) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto two_nodes = [] {
    PoseGraph g;
    g.add_node(SE3());
    g.add_node(SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)));
    return g;
  };
  auto edge = [](size_t from, size_t to, const Matrix6d& information) {
    return PoseGraphEdge{from, to, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(1, 0, 0)), information,
                         PoseGraphEdgeKind::loop};
  };
  Matrix6d asymmetric = Matrix6d::Identity();
  asymmetric(0, 1) = 0.5;
  Matrix6d indefinite = Matrix6d::Identity();
  indefinite(5, 5) = -1.0;
  Matrix6d nan_info = Matrix6d::Identity();
  nan_info(2, 2) = nan;
  struct Case {
    const char* what;
    PoseGraph graph;
  };
  std::vector<Case> cases;
  {
    PoseGraph g = two_nodes();
    g.add_node(SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(nan, 0, 0)));
    g.add_edge(edge(1, 2, Matrix6d::Identity()));
    cases.push_back({"NaN pose", std::move(g)});
  }
  for (const auto& [what, info] : {std::pair<const char*, Matrix6d>{"NaN information", nan_info},
                                   {"asymmetric information", asymmetric},
                                   {"indefinite information", indefinite},
                                   {"zero information", Matrix6d::Zero()}}) {
    PoseGraph g = two_nodes();
    g.add_edge(edge(0, 1, info));
    cases.push_back({what, std::move(g)});
  }
  {
    PoseGraph g = two_nodes();
    g.add_edge(edge(0, 2, Matrix6d::Identity()));
    cases.push_back({"edge to a missing node", std::move(g)});
  }
  {
    PoseGraph g = two_nodes();
    g.add_edge(edge(1, 1, Matrix6d::Identity()));
    cases.push_back({"self edge", std::move(g)});
  }
  {
    PoseGraph g = two_nodes();
    g.add_edge(PoseGraphEdge{0, 1, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(nan, 0, 0)),
                             Matrix6d::Identity(), PoseGraphEdgeKind::odometry});
    cases.push_back({"NaN measurement", std::move(g)});
  }
  {
    PoseGraph g = two_nodes();
    g.set_fixed(7);
    cases.push_back({"set_fixed out of range", std::move(g)});
  }
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    const PoseGraphResult r = c.graph.optimize();
    EXPECT_EQ(r.status, PoseGraphStatus::invalid);
    EXPECT_FALSE(r.message.empty());
    EXPECT_EQ(r.T_world_node.size(), c.graph.num_nodes());
    EXPECT_TRUE(all_finite(r));
  }
  // Bad options are input too.
  PoseGraph g = two_nodes();
  g.add_edge(edge(0, 1, Matrix6d::Identity()));
  PoseGraphOptions bad;
  bad.time_budget_ms = nan;
  EXPECT_EQ(g.optimize(bad).status, PoseGraphStatus::invalid);
  // A positive semi-definite information that constrains only the rotation is valid.
  PoseGraph rotation_only = two_nodes();
  Matrix6d info = Matrix6d::Zero();
  info.topLeftCorner<3, 3>().setIdentity();
  rotation_only.add_edge(edge(0, 1, info));
  const PoseGraphResult r = rotation_only.optimize();
  EXPECT_TRUE(r.ok()) << r.message;
  EXPECT_TRUE(all_finite(r));
}

// A budget too small to converge: the best solution so far, finite, with its status.
TEST(PoseGraph, IterationLimitIsReported) {
  const LoopGraph g(4);
  PoseGraphOptions options;
  options.max_iterations = 1;
  options.loop_reject_chi2 = 0.0;
  const PoseGraphResult r = g.graph.optimize(options);
  EXPECT_EQ(r.status, PoseGraphStatus::max_iterations) << r.message;
  EXPECT_TRUE(all_finite(r));
  EXPECT_LE(r.iterations, 1);
}

}  // namespace
}  // namespace hf::slam
