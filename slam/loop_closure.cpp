#include "slam/loop_closure.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace hf::slam {

void LoopClosureOptions::validate() const {
  if (candidates < 1 || candidates > 50) throw Error("loop_closure.candidates must be in [1, 50]");
  if (min_keyframe_gap < 1) throw Error("loop_closure.min_keyframe_gap must be >= 1");
  if (!(min_path_m >= 0) || !std::isfinite(min_path_m)) throw Error("loop_closure.min_path_m must be >= 0");
  if (!(max_distance_m > 0) || !std::isfinite(max_distance_m))
    throw Error("loop_closure.max_distance_m must be positive");
  if (!(max_angle_deg > 0 && max_angle_deg <= 180)) throw Error("loop_closure.max_angle_deg must be in (0, 180]");
  if (!(min_inlier_ratio >= 0 && min_inlier_ratio <= 1)) throw Error("loop_closure.min_inlier_ratio must be in [0, 1]");
  if (!(min_consistent >= 0 && min_consistent <= 1)) throw Error("loop_closure.min_consistent must be in [0, 1]");
  if (!(graph.time_budget_ms > 0) || !std::isfinite(graph.time_budget_ms))
    throw Error("loop_closure.time_budget_ms must be positive");
  if (graph.max_iterations < 1 || graph.max_iterations > 10000)
    throw Error("loop_closure.max_iterations must be in [1, 10000]");
  if (apply_delay_frames < 1 || apply_delay_frames > 10000)
    throw Error("loop_closure.apply_delay_frames must be in [1, 10000]");
  if (window_keyframes < 0 || window_keyframes > 50) throw Error("loop_closure.window_keyframes must be in [0, 50]");
  if (!(window_information_scale > 0 && window_information_scale <= 1e6))
    throw Error("loop_closure.window_information_scale must be in (0, 1e6]");
  if (!(window_tracking_information_scale >= 0 && window_tracking_information_scale <= 1e6))
    throw Error("loop_closure.window_tracking_information_scale must be in [0, 1e6]");
}

std::vector<size_t> loop_candidates(const KeyframeMap& keyframes, size_t k,
                                    const std::vector<AppearanceMatch>& matches, const LoopClosureOptions& options) {
  std::vector<bool> has_images(keyframes.size());
  for (size_t i = 0; i < keyframes.size(); ++i) has_images[i] = keyframes.has_images(i);
  return loop_candidates(keyframes.all(), has_images, k, matches, options);
}

std::vector<size_t> loop_candidates(const std::vector<Keyframe>& keyframes, const std::vector<bool>& has_images,
                                    size_t k, const std::vector<AppearanceMatch>& matches,
                                    const LoopClosureOptions& options) {
  std::vector<size_t> out;
  if (k >= keyframes.size() || has_images.size() < keyframes.size()) return out;
  const SE3& T_world_k = keyframes[k].T_world_camera;
  for (const AppearanceMatch& m : matches) {
    if (m.id >= keyframes.size() || m.id + size_t(options.min_keyframe_gap) > k) continue;
    if (!has_images[m.id]) continue;
    if (keyframes[k].path_m - keyframes[m.id].path_m < options.min_path_m) continue;
    const SE3 T_c_k = keyframes[m.id].T_world_camera.inverse() * T_world_k;
    const double angle_deg = T_c_k.angle_rad() * 180.0 / M_PI;
    if (T_c_k.translation().norm() > options.max_distance_m || angle_deg > options.max_angle_deg) continue;
    out.push_back(m.id);
    if (out.size() >= size_t(options.candidates)) break;
  }
  return out;
}

Matrix6d odometry_information(const Matrix6d& information, size_t frames) {
  // 1 mm and 0.06 degrees of standard deviation: far looser than any registration, only a floor.
  constexpr double kFloor = 1.0;
  Matrix6d info = information / double(std::max<size_t>(frames, 1));
  if (!info.allFinite()) info.setZero();
  info = 0.5 * (info + info.transpose()).eval();
  info += kFloor * Matrix6d::Identity();
  return info;
}

PoseGraph keyframe_graph(const KeyframeMap& keyframes, const std::vector<LoopEdge>& loops,
                         const std::vector<LoopEdge>& window, double tracking_information_scale) {
  return keyframe_graph(keyframes.all(), loops, window, tracking_information_scale);
}

PoseGraph keyframe_graph(const std::vector<Keyframe>& keyframes, const std::vector<LoopEdge>& loops,
                         const std::vector<LoopEdge>& window, double tracking_information_scale) {
  PoseGraph g;
  for (const Keyframe& k : keyframes) g.add_node(k.T_world_camera);
  for (size_t i = 1; i < keyframes.size(); ++i) {
    const Keyframe& a = keyframes[i - 1];
    const Keyframe& b = keyframes[i];
    PoseGraphEdge e;
    e.from = i - 1;
    e.to = i;
    if (b.odometry_information.allFinite() && b.odometry_information.trace() > 0) {
      e.T_from_to = b.T_previous_this_registered;
      e.information = odometry_information(b.odometry_information, 1);
      if (tracking_information_scale > 0.0) {
        PoseGraphEdge tracked = e;
        tracked.T_from_to = b.T_previous_this;
        tracked.information = odometry_information(tracking_information_scale * b.information,
                                                   b.frame_index - a.frame_index);
        g.add_edge(tracked);
      }
    } else {
      e.T_from_to = b.T_previous_this;
      e.information = odometry_information(b.information, b.frame_index - a.frame_index);
    }
    e.kind = PoseGraphEdgeKind::odometry;
    g.add_edge(e);
  }
  // Window edges weigh as odometry (no robust loss, never pruned by the loop consistency test); loops as loops.
  const auto add_registered = [&g](const LoopEdge& l, PoseGraphEdgeKind kind) {
    PoseGraphEdge e;
    e.from = l.from;
    e.to = l.to;
    e.T_from_to = l.T_from_to;
    e.information = l.information;
    e.kind = kind;
    g.add_edge(e);
  };
  for (const LoopEdge& w : window) add_registered(w, PoseGraphEdgeKind::odometry);
  for (const LoopEdge& l : loops) add_registered(l, PoseGraphEdgeKind::loop);
  return g;
}

}  // namespace hf::slam
