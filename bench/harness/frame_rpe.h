// RPE between consecutive frames, as the TUM benchmark's evaluate_rpe.py computes it with
// `--fixed_delta --delta 1 --delta_unit f` (Sturm et al., IROS 2012): the relative pose error of each pair of
// consecutive ESTIMATED poses. The table's RPE over 1 s (slam/eval.h) needs more than 1 s of trajectory; this
// one exists for every run of at least 3 poses (e.g. fr1/desk's 9 frames, 0.3 s), so Table 1 has an RPE on every
// input.
//
// The script, literally (delta_unit "f": index_est = range(len(traj_est))):
//   - pairs (i, j) with j = find_closest_index(index_est, i + 1), kept unless j is the last estimated pose: so
//     (i, i + 1) for i = 0 .. n - 3 (the script drops the pair ending on the last pose, as it does for seconds);
//   - the ground truth of each end is the nearest by time stamp (offset 0), the pair rejected when either is more
//     than 2 x median(ground-truth intervals) away;
//   - error = ominus(ominus(E_j, E_i), ominus(G_j, G_i)) with ominus(a, b) = a^-1 b; trans = |t(error)| in metres,
//     rot = its angle in degrees, per frame pair (not divided by any time: the script's unit is "per frame").
// A pair spans a gap of lost frames where the estimate has one (the script works on the estimate file's poses).
// Statistics: hf::ErrorStats (numpy semantics). Pure function; never throws (too few poses: empty).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <numbers>
#include <vector>

#include "io/trajectory_io.h"
#include "slam/eval.h"

namespace hf::bench {

struct FrameRpe {
  size_t pairs = 0;              // pairs kept
  size_t rejected_gap_pairs = 0; // pairs whose nearest ground truth was too far away
  ErrorStats trans_m, rot_deg;   // per consecutive-pose pair
  bool empty() const { return pairs == 0; }
};

inline FrameRpe evaluate_rpe_per_frame(const Trajectory& gt_in, const Trajectory& est_in) {
  FrameRpe result;
  if (gt_in.size() < 2 || est_in.size() < 3) return result;
  // The script sorts both stamp lists.
  auto sorted_by_stamp = [](Trajectory t) {
    std::stable_sort(t.begin(), t.end(),
                     [](const StampedPose& a, const StampedPose& b) { return a.timestamp_s < b.timestamp_s; });
    return t;
  };
  const Trajectory gt = sorted_by_stamp(gt_in), est = sorted_by_stamp(est_in);
  std::vector<double> stamps_gt;
  stamps_gt.reserve(gt.size());
  for (const StampedPose& p : gt) stamps_gt.push_back(p.timestamp_s);
  std::vector<double> intervals;
  for (size_t k = 1; k < stamps_gt.size(); ++k) intervals.push_back(stamps_gt[k] - stamps_gt[k - 1]);
  std::sort(intervals.begin(), intervals.end());
  const size_t m = intervals.size();
  const double median = m % 2 == 1 ? intervals[m / 2] : intervals[m / 2 - 1] * 0.5 + intervals[m / 2] * 0.5;
  const double max_difference_s = 2.0 * median;

  std::vector<double> trans, rot;
  // j = i + 1 for every i whose partner is not the last pose (find_closest_index over 0..n-1 of i + 1).
  for (size_t i = 0; i + 2 < est.size(); ++i) {
    const size_t j = i + 1;
    const double t0 = est[i].timestamp_s, t1 = est[j].timestamp_s;
    const size_t g0 = find_closest_index(stamps_gt, t0), g1 = find_closest_index(stamps_gt, t1);
    if (std::fabs(stamps_gt[g0] - t0) > max_difference_s || std::fabs(stamps_gt[g1] - t1) > max_difference_s) {
      ++result.rejected_gap_pairs;
      continue;
    }
    const SE3& E0 = est[i].T_world_camera;
    const SE3& E1 = est[j].T_world_camera;
    const SE3& G0 = gt[g0].T_world_camera;
    const SE3& G1 = gt[g1].T_world_camera;
    const SE3 error = (E1.inverse() * E0).inverse() * (G1.inverse() * G0);
    trans.push_back(error.translation().norm());
    rot.push_back(rotation_angle_rad(error.quaternion()) * 180.0 / std::numbers::pi);
  }
  result.pairs = trans.size();
  result.trans_m = compute_error_stats(trans);
  result.rot_deg = compute_error_stats(rot);
  return result;
}

}  // namespace hf::bench
