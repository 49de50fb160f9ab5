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
// slam/eval.h's evaluate_rpe in frame units (RpeOptions::delta_frames = 1) computes it; this names the result.
// Statistics: hf::ErrorStats (numpy semantics). Pure function; never throws (too few poses: empty).
#pragma once

#include <algorithm>
#include <cstddef>
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
  // The script sorts both stamp lists; slam/eval.h's RPE reads them in the given order.
  auto sorted_by_stamp = [](Trajectory t) {
    std::stable_sort(t.begin(), t.end(),
                     [](const StampedPose& a, const StampedPose& b) { return a.timestamp_s < b.timestamp_s; });
    return t;
  };
  const RpeResult rpe = evaluate_rpe(sorted_by_stamp(gt_in), sorted_by_stamp(est_in), {.delta_frames = 1});
  FrameRpe result;
  result.pairs = rpe.pairs.size();
  result.rejected_gap_pairs = rpe.rejected_gap_pairs;
  result.trans_m = rpe.trans_m_per_s;  // per frame: delta_frames = 1
  result.rot_deg = rpe.rot_deg_per_s;
  return result;
}

}  // namespace hf::bench
