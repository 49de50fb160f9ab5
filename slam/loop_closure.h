// Loop closure over keyframes: candidates, the keyframe pose graph, and what a closed loop changes.
//
//   std::vector<size_t> c = loop_candidates(keyframes, k, appearance_matches, options);
//   ... verify each candidate by registration (the pipeline does: slam/pipeline.h, stage `close_loops`) ...
//   PoseGraph g = keyframe_graph(keyframes, loops);
//   PoseGraphResult res = g.optimize(options.graph);
//
// Candidates (DVO-SLAM / ElasticFusion style): keyframes the new keyframe's appearance retrieves that are at least
// min_keyframe_gap keyframes older (the recent ones are chained by odometry already), at least min_path_m of
// camera path back (a loop is only worth closing when drift had a path to accumulate over: a camera turning on the
// spot keeps seeing what frame-to-model tracking already aligns against) AND whose current pose lies within
// max_distance_m and max_angle_deg of the new keyframe's: appearance alone confuses repeated structure, and drift
// over a loop is far below a metre. Verification, then the pose graph's robust loss and its chi^2
// consistency test (slam/pose_graph.h), stand between a candidate and the map.
//
// The graph: one node per keyframe (node 0 fixed: the map's gauge); odometry edges between consecutive keyframes
// carrying their relative pose as tracked, with the information of the registration that placed the later one
// divided by the frames between them (frame-to-model errors add up frame by frame, so the variance grows with the
// gap); loop edges from the verifying registration's T_candidate_keyframe and information.
#pragma once

#include <cstddef>
#include <vector>

#include "core/se3.h"
#include "slam/appearance.h"
#include "slam/keyframes.h"
#include "slam/pose_graph.h"

namespace hf::slam {

struct LoopClosureOptions {
  bool enabled = true;
  int candidates = 3;            // appearance matches verified per new keyframe (best first)
  // Chosen on the synthetic `loop` preset (tests/slam/test_slam_recovery.cpp), checked for false loops on the real
  // sequences (bench/results/tracking.md): the view that comes back after a lap overlaps the first keyframe by
  // a third to a half, seen up to ~60 degrees apart.
  int min_keyframe_gap = 5;      // candidates are at least this many keyframes older
  // and at least this much camera path back. Without it (0) loops closed on TUM fr1/rpy 0-149 lowered ATE 1.96 ->
  // 1.88 cm, but on the report part (frames 150-269) raised it 1.87 -> 2.25 cm: rotation on the spot makes
  // "loops" between keyframes centimetres apart whose over-confident information only adds noise
  // (bench/results/tracking.md). The synthetic lap is 3.1 m.
  double min_path_m = 1.0;
  double max_distance_m = 1.0;   // pose proximity of a candidate (translation between the two poses)
  double max_angle_deg = 60.0;   // and rotation
  double min_inlier_ratio = 0.3;  // the verifying registration's inlier ratio (status must be good)
  double min_consistent = 0.6;   // share of the overlapping depth that agrees after verification
  PoseGraphOptions graph;        // Ceres solve (robust loss, consistency test, time budget: realtime mode only)
  // The back-end (slam/backend.h): jobs run on their own thread beside tracking (true) or inline on the tracking
  // thread at their snapshot (false: the same results, the cost on the frame). A job snapshotted at frame s is
  // applied before frame s + apply_delay_frames is tracked. A correction that lands late is tracked against for
  // longer at the old map: on the synthetic lap (250 frames, 640x480) ATE 1.39 mm at 1, 1.40 at 3, 2.60 at 10 (loop
  // closure off: 3.81; bench/results/backend.md). 3 frames (~100 ms at 30 Hz) fit a job's verification and solve
  // (tens of ms on an unloaded core) beside tracking, so the tracker rarely waits.
  bool background = true;
  int apply_delay_frames = 3;
  // Keyframe window edges (DVO-SLAM's local constraints): each new keyframe k is also registered densely against
  // keyframes k-2 .. k-window_keyframes (k-1 is its odometry edge already), from the relative pose of their current
  // poses, verified as a loop is (min_inlier_ratio, min_consistent, no degenerate direction), and the graph is
  // solved at every keyframe that added one, loop or not. 0 or 1 = off (the graph is solved only when a loop
  // closes). Cost: up to window_keyframes - 1 registrations at the tracking level and one solve per keyframe, on the
  // back-end's thread, and the re-fusions the solves call for. Off by default: no setting tried kept both choice
  // parts no worse (bench/results/accuracy/ate_levers.md, session 7).
  int window_keyframes = 0;
  // The window edge's information is the registration's J^T W J times this: two frames' registration errors are
  // correlated (bias, not white noise), so their J^T W J overstates what they know (the failure of near loops:
  // bench/results/tracking.md). In (0, 1e6].
  double window_information_scale = 1.0;
  // With window edges on (and only then), the tracked relative pose of consecutive keyframes (frame-to-model,
  // Keyframe::T_previous_this) is kept in the graph beside the registered chain, its information
  // (odometry_information of the tracking registration over the frames between) times this; 0 = left out (the
  // graph then holds keyframe registrations alone, and each solve replaces the model-tracked poses with theirs).
  double window_tracking_information_scale = 0.0;
  // window_tracking_information_scale when window edges are on (window_keyframes >= 2), else 0.
  double tracking_information_scale_in_graph() const {
    return window_keyframes >= 2 ? window_tracking_information_scale : 0.0;
  }

  void validate() const;  // hf::Error naming the bad field
};

// A verified loop: T_world_to = T_world_from * T_from_to, from = the older keyframe.
struct LoopEdge {
  size_t from = 0, to = 0;
  SE3 T_from_to;
  Matrix6d information = Matrix6d::Identity();
};

// The keyframes worth verifying against keyframe k, best appearance first (see the header comment).
std::vector<size_t> loop_candidates(const KeyframeMap& keyframes, size_t k,
                                    const std::vector<AppearanceMatch>& matches, const LoopClosureOptions& options);
// The same over keyframes held as values (the back-end's snapshot, slam/backend.h): has_images[i] says whether
// keyframe i can still be registered against.
std::vector<size_t> loop_candidates(const std::vector<Keyframe>& keyframes, const std::vector<bool>& has_images,
                                    size_t k, const std::vector<AppearanceMatch>& matches,
                                    const LoopClosureOptions& options);

// The pose graph over every keyframe (current poses as the initial values) with the odometry chain and `loops`.
// An odometry edge is the keyframe-to-keyframe registration where one was measured (Keyframe::
// odometry_information non-zero), else the tracked relative pose. `window` edges (LoopClosureOptions::
// window_keyframes; their information as the graph uses it, scaled when measured) join as odometry edges (no robust
// loss, never rejected: each was verified). tracking_information_scale > 0 adds, for each consecutive pair whose
// chain edge is a registration, the tracked relative pose as a second odometry edge with its information times
// that scale (LoopClosureOptions::window_tracking_information_scale).
PoseGraph keyframe_graph(const KeyframeMap& keyframes, const std::vector<LoopEdge>& loops,
                         const std::vector<LoopEdge>& window = {}, double tracking_information_scale = 0.0);
PoseGraph keyframe_graph(const std::vector<Keyframe>& keyframes, const std::vector<LoopEdge>& loops,
                         const std::vector<LoopEdge>& window = {}, double tracking_information_scale = 0.0);

// Information of an odometry edge spanning `frames` frames whose later end was placed with `information`: the
// information divided by the frames (at least 1), floored at a small multiple of the identity so a keyframe placed
// without registration (the first, or a relocalised one) never leaves the graph disconnected or singular.
Matrix6d odometry_information(const Matrix6d& information, size_t frames);

}  // namespace hf::slam
