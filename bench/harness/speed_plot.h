// speed_vs_error.png: one labelled point per method, milliseconds per frame on x and ATE RMSE on y (both lower is
// better, so the best corner is the lower left), the Pareto front joined by a dashed step line and its points
// ringed. An axis is logarithmic when its data span more than a factor of 10, else linear. Peers are drawn as
// squares, hashfusion methods as discs. Methods without a comparable ATE (or with a time or error beyond 1e12, no
// plottable range) are listed under the plot as "not plotted"; the footer is wrapped to the canvas's width (at
// most a third of its height, then cut with a count); every tick and dash loop is bounded by a count.
// Drawn with OpenCV in the style of slam/eval_plot.cpp.
// Thread-safety: pure functions. Failures: hf::Error (size out of range, a file that cannot be written).
#pragma once

#include <string>
#include <vector>

#include "core/image.h"

namespace hf::bench {

struct SpeedPoint {
  std::string label;     // e.g. "combined", "gicp (peer)"
  double ms_per_frame = 0.0;
  double ate_m = 0.0;
  bool peer = false;
};

struct SpeedPlotOptions {
  int width_px = 1100;   // at least 400
  int height_px = 800;   // at least 300
  std::string title;     // first line; e.g. "synthetic:wall" or "all inputs"
  std::string subtitle;  // second line (what the numbers are), may be empty
  std::vector<std::string> not_plotted;  // labels of methods without a point (failed / lost)
};

ColorImage render_speed_plot(const std::vector<SpeedPoint>& points, const SpeedPlotOptions& options);
// Renders and writes a PNG atomically (core/atomic_file.h).
void write_speed_plot(const std::string& path, const std::vector<SpeedPoint>& points,
                      const SpeedPlotOptions& options);

}  // namespace hf::bench
