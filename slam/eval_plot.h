// A picture of an ATE evaluation: the ground truth and the aligned estimate seen "from above", the estimate
// coloured by its per-pose ATE error, the way evaluate_ate.py --plot draws it but with the error as colour.
//
// What is drawn:
// - Projection: the two world axes along which the ground-truth positions (of the drawn span) vary most; the
//   axis of least variance is dropped (for TUM ground truth that is usually z, the height, giving the top view
//   x-y; for camera-convention worlds with y down it is usually y, giving x-z). The kept axes are drawn in
//   x, y, z order, the first to the right and the second up, with the same metres per pixel on both (equal
//   aspect), ticks at 1/2/5 x 10^k metres and labels "x [m]" etc. TrajectoryPlotOptions::drop_axis overrides.
// - Ground truth: black, over the time span of the associated pairs only (a benchmark's ground truth often
//   runs far longer than the evaluated estimate).
// - Estimate: every pose mapped by the ATE alignment T_gt_est (thin grey where a pose has no ground-truth
//   partner); the segments between associated poses are coloured by ATE error (viridis, 0 m dark blue to the
//   maximum error yellow), with a colour bar labelled in metres; thin grey lines join each associated estimate
//   pose to its ground-truth pose (the "difference" lines of evaluate_ate.py).
// - Title: the caller's title (e.g. the file names) and "ATE RMSE ... m over N pairs" (+ RPE when present);
//   a legend in the corner of the plot that hides the fewest drawn poses.
// Thread-safety: pure functions. Failures: hf::Error (see each function).
#pragma once

#include <string>

#include "core/image.h"
#include "io/trajectory_io.h"
#include "slam/eval.h"

namespace hf {

struct TrajectoryPlotOptions {
  int width_px = 1100;  // at least 400
  int height_px = 850;  // at least 300
  int drop_axis = -1;   // -1: automatic (see above); 0, 1, 2: drop x, y or z
  std::string title;    // first title line; empty: "ground truth vs aligned estimate"
};

// Renders the plot of `result` (from evaluate_trajectory(gt, est) on these same trajectories) as RGB.
// Throws hf::Error when the sizes or drop_axis are out of range, result's indices do not fit the trajectories, or
// a drawn position or the largest error is not finite or beyond 1e9 m (no plot of such a range means anything;
// every loop here is bounded by a count, so no input can make it spin).
ColorImage render_trajectory_plot(const Trajectory& gt, const Trajectory& est, const EvalResult& result,
                                  const TrajectoryPlotOptions& options = {});

// Renders and writes a PNG (any extension OpenCV encodes) atomically (core/atomic_file.h). Throws hf::Error
// naming the file when encoding or writing fails, and as render_trajectory_plot.
void write_trajectory_plot(const std::string& path, const Trajectory& gt, const Trajectory& est,
                           const EvalResult& result, const TrajectoryPlotOptions& options = {});

}  // namespace hf
