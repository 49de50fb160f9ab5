// Trajectory evaluation exactly as the TUM RGB-D benchmark scripts (Sturm et al., IROS 2012):
// evaluate_ate.py (absolute trajectory error) and evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s
// (relative pose error per second). Both trajectories are T_world_camera in TUM format (io/trajectory_io.h),
// timestamps in seconds, positions in metres.
//
// ATE (evaluate_ate.py):
//   1. Association exactly as associate.py (io/associate.h) with first list = ground truth, second list =
//      estimate: a pair (g, e) needs |t_g - (t_e + offset_s)| < max_difference_s, greedy by smallest difference.
//   2. Horn's closed-form rigid alignment without scale of the estimated positions ("model") onto the ground-truth
//      positions ("data"), the script's align(): both sets zero-centred, W = sum model_c data_c^T,
//      U d V^T = svd(W^T), S = diag(1, 1, -1) when det(U) det(V) < 0 else I, R = U S V^T,
//      t = mean(data) - R mean(model). The result is T_gt_est = (R, t): it maps estimate-world points into the
//      ground-truth world.
//   3. Per associated pair, error_m = |R p_est + t - p_gt|; statistics with numpy semantics (ErrorStats).
//   The script accepts 2 pairs; we require at least 3 (kMinAtePairs): with 2 (or collinear) positions the
//   rotation about their line is not determined, so the aligned estimate and its plot would be arbitrary.
//   Orientation does not enter ATE (as in the script).
//
// RPE (evaluate_rpe.py evaluate_trajectory() with param_fixed_delta=True, param_delta_unit="s", scale 1):
//   1. For every estimated pose i, j = find_closest_index(est stamps, t_i + delta_s); the pair (i, j) is kept
//      unless j is the last estimated pose (the script's `if j != len(traj_est)-1`, which drops the pairs whose
//      partner would run past the end of the estimate, and the one that lands exactly on the last pose). As in
//      the script, j may equal i where the estimate has a gap longer than delta around t_i + delta (error 0).
//   2. The ground-truth poses for t_i + offset_s and t_j + offset_s are the nearest by timestamp
//      (find_closest_index on the ground-truth stamps). The pair is rejected when either nearest ground-truth
//      stamp is more than 2 x median(ground-truth stamp intervals) away (numpy median).
//   3. error = (E_j^-1 E_i)^-1 (G_j^-1 G_i), literally the script's ominus(ominus(est_1, est_0),
//      ominus(gt_1, gt_0)) with ominus(a, b) = a^-1 b. Note this is NOT (G_i^-1 G_j)^-1 (E_i^-1 E_j): the two
//      have the same rotation angle but their translations differ when the relative rotations differ; we follow
//      the script. trans = |t(error)|, rot = rotation angle of error in [0, pi].
//   4. "Per second": the script reports the error over a delta of 1 s as m/s and deg/s without dividing; we
//      divide by delta_s, which is the same number for the benchmark's delta = 1 s and keeps the unit honest
//      for other deltas.
//   Choices where the script is undefined or fragile:
//   - The script raises when fewer than 2 pairs survive; we return an RPE with no pairs (RpeResult::empty()),
//     which the JSON reports as null fields and rpe_pairs 0: a trajectory shorter than delta is not an error.
//     A single surviving pair is reported.
//   - The rotation angle is computed as 2 atan2(|q.vec|, |q.w|) of the error's unit quaternion instead of
//     arccos((trace(R) - 1) / 2): identical in exact arithmetic, but accurate near 0 (where arccos of a number
//     close to 1 loses half the digits, ~1e-8 rad) and near pi.
//   - The script subsamples to 10000 random pairs by default (--max_pairs); we evaluate every pair, i.e. the
//     script with --max_pairs 0, which is identical whenever there are at most 10000 pairs (5.5 min at 30 Hz).
//
// Statistics (ErrorStats), numpy semantics: rmse = sqrt(sum e^2 / n), mean, median (the average of the two middle
// values for even n), std = population standard deviation (ddof = 0), min, max.
//
// Thread-safety: all functions are pure (no shared state). Failures throw hf::Error with a message naming what
// is wrong (no pairs, too few pairs, empty trajectory, bad options); nothing prints.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/se3.h"
#include "io/trajectory_io.h"

namespace hf {

// Fewer associated pairs than this make evaluate_ate throw (see above).
inline constexpr size_t kMinAtePairs = 3;

// Summary of non-negative error values with numpy's definitions. count = 0 means "no values" (all fields 0).
struct ErrorStats {
  size_t count = 0;
  double rmse = 0.0, mean = 0.0, median = 0.0, std = 0.0, min = 0.0, max = 0.0;
};
ErrorStats compute_error_stats(const std::vector<double>& values);

// evaluate_rpe.py's find_closest_index: binary search over the ascending list L for t, keeping the element with
// the smallest |L[k] - t| seen (the first one on ties); returns 0 for an empty list.
size_t find_closest_index(const std::vector<double>& sorted, double t);

// Rotation angle of a unit quaternion in [0, pi], accurate near 0 and pi (see above).
double rotation_angle_rad(const Eigen::Quaterniond& q);

// Horn's closed-form alignment exactly as evaluate_ate.py's align(model, data): T_data_model minimising
// sum |R model_k + t - data_k|^2. Sizes must match and be >= 1; throws hf::Error otherwise.
SE3 align_horn(const std::vector<Eigen::Vector3d>& model, const std::vector<Eigen::Vector3d>& data);

struct AteOptions {
  double max_difference_s = 0.02;  // associate.py --max_difference
  double offset_s = 0.0;           // added to the estimate's stamps (associate.py --offset)
};

struct AtePair {
  size_t gt_index = 0, est_index = 0;  // into the trajectories passed in
  double gt_stamp_s = 0.0, est_stamp_s = 0.0;
  double error_m = 0.0;  // |T_gt_est p_est - p_gt| after alignment
};

struct AteResult {
  SE3 T_gt_est;                // the alignment: estimate world -> ground-truth world
  std::vector<AtePair> pairs;  // sorted by ground-truth stamp (associate.py order)
  ErrorStats error_m;
};

// Throws hf::Error when a trajectory is empty, the options are not finite / max_difference_s <= 0, no pair is
// within max_difference_s ("no pose pairs within 0.02 s ..."), or fewer than kMinAtePairs pairs are.
AteResult evaluate_ate(const Trajectory& gt, const Trajectory& est, const AteOptions& options = {});

// The estimate mapped into the ground-truth world: T_gt_est * T_world_camera for every pose (orientation too).
Trajectory apply_alignment(const Trajectory& est, const SE3& T_gt_est);

struct RpeOptions {
  double delta_s = 1.0;   // evaluate_rpe.py --delta (unit s)
  double offset_s = 0.0;  // evaluate_rpe.py --offset, added to the estimate's stamps
  // > 0: the script's --delta_unit f instead: pairs (i, i + delta_frames) of ESTIMATED poses (its index list is
  // range(len(traj_est)), so j = min(i + delta_frames, last) and the pair is kept unless j is the last pose), and
  // the errors divided by delta_frames (per frame) rather than by delta_s. Otherwise as above.
  int delta_frames = 0;
};

struct RpePair {
  size_t est_index_0 = 0, est_index_1 = 0, gt_index_0 = 0, gt_index_1 = 0;
  double est_stamp_0_s = 0.0, est_stamp_1_s = 0.0, gt_stamp_0_s = 0.0, gt_stamp_1_s = 0.0;
  double trans_m_per_s = 0.0;  // |t(error)| / delta_s (/ delta_frames in frame units: metres per frame)
  double rot_deg_per_s = 0.0;  // angle(error) in degrees / delta_s (/ delta_frames: degrees per frame)
};

struct RpeResult {
  std::vector<RpePair> pairs;             // in order of est_index_0
  size_t rejected_gap_pairs = 0;          // pairs dropped because the nearest ground truth was too far away
  double gt_max_time_difference_s = 0.0;  // 2 x median ground-truth interval (0 when gt has < 2 poses)
  double delta_s = 1.0;                   // the options' delta
  ErrorStats trans_m_per_s, rot_deg_per_s;
  bool empty() const { return pairs.empty(); }
};

// Never throws for short or non-overlapping trajectories (the result is then empty); throws hf::Error only for
// a non-finite or non-positive delta_s, a negative delta_frames or a non-finite offset_s.
RpeResult evaluate_rpe(const Trajectory& gt, const Trajectory& est, const RpeOptions& options = {});

// The numbers a report embeds: plain values, no I/O. RPE fields are absent (nullopt) when there is no RPE pair.
struct TrajectoryMetrics {
  size_t pairs = 0;  // ATE pairs
  ErrorStats ate_m;
  size_t rpe_pairs = 0;
  std::optional<ErrorStats> rpe_trans_m_per_s, rpe_rot_deg_per_s;
  double rpe_delta_s = 1.0;
};

struct EvalOptions {
  double max_difference_s = 0.02;
  double offset_s = 0.0;
  double rpe_delta_s = 1.0;
};

struct EvalResult {
  AteResult ate;
  RpeResult rpe;
  TrajectoryMetrics metrics() const;
};

// ATE and RPE together with shared offset; throws as evaluate_ate.
EvalResult evaluate_trajectory(const Trajectory& gt, const Trajectory& est, const EvalOptions& options = {});

// {"pairs", "ate_rmse_m", "ate_mean_m", "ate_median_m", "ate_std_m", "ate_min_m", "ate_max_m", "rpe_pairs",
//  "rpe_delta_s", "rpe_trans_{rmse,mean,median,std,min,max}_m_per_s", "rpe_rot_{...}_deg_per_s"}; the rpe_*
// statistics are null when rpe_pairs is 0. Never contains NaN.
nlohmann::json metrics_to_json(const TrajectoryMetrics& metrics);
// Per-pose ATE and per-pair RPE values: {"ate": [{"gt_stamp_s", "est_stamp_s", "error_m"}...],
// "rpe": [{"est_stamp_0_s", "est_stamp_1_s", "gt_stamp_0_s", "gt_stamp_1_s", "trans_m_per_s", "rot_deg_per_s"}...]}.
nlohmann::json per_frame_to_json(const EvalResult& result);
// A short aligned plain-text table (for the terminal) and the same as a Markdown table (for reports).
std::string format_metrics_table(const TrajectoryMetrics& metrics);
std::string format_metrics_markdown(const TrajectoryMetrics& metrics);

}  // namespace hf
