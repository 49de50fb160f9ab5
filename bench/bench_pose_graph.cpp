// The keyframe pose graph (slam/pose_graph.h): ms per optimize() on synthetic graphs of 100 .. 1000 nodes.
//
//   BM_PoseGraph/<nodes>/<false loops>   nodes on four laps of a 2 m circle (a camera circling a room), odometry
//                                        edges between consecutive nodes with 1 cm / 0.57 degree Gaussian noise,
//                                        a loop edge from every 5th node of laps 2-4 to the node one lap before
//                                        (the same noise), plus <false loops> loop edges that are 3 m and 90
//                                        degrees wrong (rejected by the consistency test: a second solve).
// Initial poses are dead reckoned. Counters: iterations, final RMS translation error against the truth (m), and
// that of dead reckoning. Results: bench/results/pose_graph.md.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "slam/pose_graph.h"

namespace {

using hf::Matrix6d;
using hf::SE3;
using hf::Vector6d;
using hf::slam::PoseGraph;
using hf::slam::PoseGraphEdge;
using hf::slam::PoseGraphEdgeKind;

struct Graph {
  PoseGraph graph;
  std::vector<SE3> truth;
};

Graph make_graph(int nodes, int false_loops) {
  constexpr int kLaps = 4;
  constexpr double kSigmaRot = 0.01, kSigmaTrans = 0.01;
  std::mt19937 rng(7);
  std::normal_distribution<double> N(0.0, 1.0);
  const int per_lap = nodes / kLaps;
  Graph g;
  for (int i = 0; i < nodes; ++i) {
    const double a = 2.0 * M_PI * i / per_lap;
    g.truth.emplace_back(Eigen::Matrix3d(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())),
                         Eigen::Vector3d(2.0 * std::cos(a), 2.0 * std::sin(a), 0.1 * std::sin(3.0 * a)));
  }
  Vector6d d;
  d << Eigen::Vector3d::Constant(1.0 / (kSigmaRot * kSigmaRot)), Eigen::Vector3d::Constant(1.0 / (kSigmaTrans * kSigmaTrans));
  const Matrix6d information = d.asDiagonal();
  auto measured = [&](int from, int to) {
    Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = (k < 3 ? kSigmaRot : kSigmaTrans) * N(rng);
    return g.truth[size_t(from)].inverse() * g.truth[size_t(to)] * SE3::exp(xi);
  };
  SE3 T = g.truth[0];
  g.graph.add_node(T);
  for (int i = 1; i < nodes; ++i) {
    const SE3 step = measured(i - 1, i);
    T = T * step;
    g.graph.add_node(T);
    g.graph.add_edge(PoseGraphEdge{size_t(i - 1), size_t(i), step, information, PoseGraphEdgeKind::odometry});
  }
  for (int i = per_lap; i < nodes; i += 5)
    g.graph.add_edge(PoseGraphEdge{size_t(i - per_lap), size_t(i), measured(i - per_lap, i), information,
                                   PoseGraphEdgeKind::loop});
  for (int k = 0; k < false_loops; ++k) {
    const int from = (nodes / 7 + 13 * k) % nodes, to = (from + per_lap / 2) % nodes;
    Vector6d wrong;
    wrong << 0.0, M_PI / 2, 0.0, 3.0, 0.0, 0.0;
    g.graph.add_edge(PoseGraphEdge{size_t(from), size_t(to),
                                   g.truth[size_t(from)].inverse() * g.truth[size_t(to)] * SE3::exp(wrong),
                                   100.0 * information, PoseGraphEdgeKind::loop});
  }
  return g;
}

double rms_m(const std::vector<SE3>& estimate, const std::vector<SE3>& truth) {
  double sum = 0.0;
  for (size_t i = 0; i < truth.size(); ++i) sum += (estimate[i].translation() - truth[i].translation()).squaredNorm();
  return std::sqrt(sum / double(truth.size()));
}

void BM_PoseGraph(benchmark::State& state) {
  const Graph g = make_graph(int(state.range(0)), int(state.range(1)));
  hf::slam::PoseGraphOptions options;
  options.time_budget_ms = 60e3;  // measure the solve, not the budget
  hf::slam::PoseGraphResult r;
  for (auto _ : state) {
    r = g.graph.optimize(options);
    benchmark::DoNotOptimize(r.final_cost);
  }
  size_t rejected = 0;
  for (bool accepted : r.loop_accepted) rejected += accepted ? 0 : 1;
  state.counters["iterations"] = r.iterations;
  state.counters["edges"] = double(g.graph.num_edges());
  state.counters["loops_rejected"] = double(rejected);
  state.counters["rms_m"] = rms_m(r.T_world_node, g.truth);
  state.counters["dead_reckoned_rms_m"] = rms_m(g.graph.initial_poses(), g.truth);
  state.counters["converged"] = r.status == hf::slam::PoseGraphStatus::converged ? 1 : 0;
}
BENCHMARK(BM_PoseGraph)
    ->Args({100, 0})
    ->Args({300, 0})
    ->Args({1000, 0})
    ->Args({100, 1})
    ->Args({1000, 3})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
