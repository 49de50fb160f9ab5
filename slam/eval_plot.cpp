#include "slam/eval_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/number_text.h"
#include "io/image_io.h"

namespace hf {
namespace {

const cv::Scalar kWhite(255, 255, 255), kBlack(0, 0, 0), kGrid(232, 232, 232), kAxis(90, 90, 90), kLink(175, 175, 245),
    kUnmatched(150, 150, 150);  // BGR: light red difference lines, grey
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr int kShift = 4;  // sub-pixel bits for cv::line / cv::circle
constexpr double kSub = 1 << kShift;
// The largest coordinate a plot accepts: beyond any trajectory (the readers stop at 1e6 m), far below where the
// pixel arithmetic (metres / metres-per-pixel, in doubles and then ints) loses its meaning.
constexpr double kMaxPlotCoordinateM = 1e9;

std::string format(double value, int decimals) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.*f", std::max(0, decimals), value);
  std::string s = buffer;
  if (s == "-0" || s.rfind("-0.", 0) == 0) {  // "-0.000" reads badly on a tick
    bool all_zero = s.find_first_not_of("-0.") == std::string::npos;
    if (all_zero) s.erase(0, 1);
  }
  return s;
}

// 1, 2 or 5 x 10^k, the smallest not below raw.
double nice_step(double raw) {
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw * (1 - 1e-9)) return m * p;
  }
  return 10.0 * p;
}

int decimals_for(double step) { return std::max(0, int(-std::floor(std::log10(step) + 1e-9))); }

// The multiples of `step` in [lo, hi], computed from a count: a loop "v <= hi; v += step" never ends once hi is
// inf, or once v is so large that v + step == v. Callers keep the range finite; the count is capped besides.
std::vector<double> trajectory_plot_ticks(double lo, double hi, double step) {
  std::vector<double> ticks;
  const double first = std::ceil(lo / step), last = std::floor(hi / step);
  if (!(std::isfinite(first) && std::isfinite(last)) || last < first) return ticks;
  const double count = std::min(last - first + 1.0, 1000.0);  // nice_step gives about 7-15; never more than 1000
  for (int k = 0; k < int(count); ++k) ticks.push_back((first + k) * step);
  return ticks;
}

void text(cv::Mat& img, const std::string& s, cv::Point origin, double scale, const cv::Scalar& colour,
          int thickness = 1) {
  cv::putText(img, s, origin, kFont, scale, colour, thickness, cv::LINE_AA);
}

cv::Size text_size(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

// Viridis lookup through OpenCV's colour map; t in [0, 1].
struct ColourMap {
  cv::Mat lut;  // 256 x 1 BGR
  ColourMap() {
    cv::Mat ramp(256, 1, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<uchar>(i) = uchar(i);
    cv::applyColorMap(ramp, lut, cv::COLORMAP_VIRIDIS);
  }
  cv::Scalar operator()(double t) const {
    const int i = std::clamp(int(std::lround(t * 255.0)), 0, 255);
    const cv::Vec3b c = lut.at<cv::Vec3b>(i);
    return cv::Scalar(c[0], c[1], c[2]);
  }
};

int choose_drop_axis(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= double(std::max<size_t>(1, points.size()));
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (const auto& p : points) var += (p - mean).cwiseAbs2();
  int axis = 2;  // ties (e.g. a single point) prefer dropping z: the top view of a z-up world
  for (int k = 1; k >= 0; --k) {
    if (var[k] < var[axis]) axis = k;
  }
  return axis;
}

}  // namespace

ColorImage render_trajectory_plot(const Trajectory& gt, const Trajectory& est, const EvalResult& result,
                                  const TrajectoryPlotOptions& options) {
  if (options.width_px < 400 || options.height_px < 300 || options.width_px > 8000 || options.height_px > 8000) {
    throw Error("trajectory plot: size must be within 400x300 .. 8000x8000 px, got " +
                std::to_string(options.width_px) + "x" + std::to_string(options.height_px));
  }
  if (options.drop_axis < -1 || options.drop_axis > 2) {
    throw Error("trajectory plot: drop_axis must be -1, 0, 1 or 2, got " + std::to_string(options.drop_axis));
  }
  const std::vector<AtePair>& pairs = result.ate.pairs;
  if (pairs.empty()) throw Error("trajectory plot: the evaluation has no ATE pairs");
  for (const AtePair& p : pairs) {
    if (p.gt_index >= gt.size() || p.est_index >= est.size()) {
      throw Error("trajectory plot: the evaluation does not belong to these trajectories (pose index out of range)");
    }
  }

  // Geometry in the ground-truth world.
  const size_t gt_first = pairs.front().gt_index, gt_last = pairs.back().gt_index;
  std::vector<Eigen::Vector3d> gt_points;
  for (size_t k = gt_first; k <= gt_last; ++k) gt_points.push_back(gt[k].T_world_camera.translation());
  const Trajectory aligned = apply_alignment(est, result.ate.T_gt_est);
  const int drop = options.drop_axis >= 0 ? options.drop_axis : choose_drop_axis(gt_points);
  const int ax0 = drop == 0 ? 1 : 0, ax1 = drop == 2 ? 1 : 2;
  const char* axis_names[] = {"x", "y", "z"};

  // A position no camera reaches (or one that is not finite) would make every range below inf or meaningless.
  auto check_drawable = [](const Eigen::Vector3d& p) {
    const double far = p.allFinite() ? p.cwiseAbs().maxCoeff() : INFINITY;  // maxCoeff may skip a NaN
    if (!(far <= kMaxPlotCoordinateM))
      throw Error("trajectory plot: a position at " + number_for_message(far) +
                  " m is beyond the 1e9 m a plot can show (is a pose corrupt?); not plotted");
  };
  for (const auto& p : gt_points) check_drawable(p);
  for (const StampedPose& pose : aligned) check_drawable(pose.T_world_camera.translation());

  double lo0 = INFINITY, hi0 = -INFINITY, lo1 = INFINITY, hi1 = -INFINITY;
  auto extend = [&](const Eigen::Vector3d& p) {
    lo0 = std::min(lo0, p[ax0]);
    hi0 = std::max(hi0, p[ax0]);
    lo1 = std::min(lo1, p[ax1]);
    hi1 = std::max(hi1, p[ax1]);
  };
  for (const auto& p : gt_points) extend(p);
  for (const AtePair& p : pairs) extend(aligned[p.est_index].T_world_camera.translation());
  // Unassociated estimate poses are drawn too, but only those inside the evaluated time span widen the view.
  for (const StampedPose& pose : aligned) {
    if (pose.timestamp_s >= pairs.front().est_stamp_s && pose.timestamp_s <= pairs.back().est_stamp_s) {
      extend(pose.T_world_camera.translation());
    }
  }
  if (!(result.ate.error_m.max <= 2 * kMaxPlotCoordinateM))
    throw Error("trajectory plot: the largest ATE error (" + number_for_message(result.ate.error_m.max) +
                " m) is not a plottable range; not plotted");
  const double span = std::max({hi0 - lo0, hi1 - lo1, 1e-3});  // a still camera still gets a 1 mm window
  const double pad = 0.06 * span;
  lo0 -= pad, hi0 += pad, lo1 -= pad, hi1 += pad;
  if (hi0 - lo0 < 0.25 * span) {  // keep degenerate (line-like) extents from collapsing the view
    const double c = 0.5 * (lo0 + hi0);
    lo0 = c - 0.125 * span, hi0 = c + 0.125 * span;
  }
  if (hi1 - lo1 < 0.25 * span) {
    const double c = 0.5 * (lo1 + hi1);
    lo1 = c - 0.125 * span, hi1 = c + 0.125 * span;
  }

  const int W = options.width_px, H = options.height_px;
  const double font = std::clamp(std::min(H / 1500.0, W / 1950.0), 0.35, 1.2);

  const std::string title_line = options.title.empty() ? "ground truth vs aligned estimate" : options.title;
  double title_font = font * 1.25;
  while (title_font > 0.3 && text_size(title_line, title_font, 2).width > W - 8) title_font *= 0.9;
  std::vector<std::string> metric_lines;
  {
    const TrajectoryMetrics m = result.metrics();
    char ate[128], rpe[128];
    std::snprintf(ate, sizeof ate, "ATE RMSE %.4f m over %zu pairs (max %.4f m)", m.ate_m.rmse, m.pairs, m.ate_m.max);
    metric_lines.push_back(ate);
    if (m.rpe_trans_m_per_s) {
      std::snprintf(rpe, sizeof rpe, "RPE RMSE %.4f m/s, %.3f deg/s over %zu pairs", m.rpe_trans_m_per_s->rmse,
                    m.rpe_rot_deg_per_s->rmse, m.rpe_pairs);
      const std::string joined = metric_lines[0] + "    " + rpe;
      if (text_size(joined, font).width <= W - 8) {
        metric_lines[0] = joined;
      } else {
        metric_lines.push_back(rpe);
      }
    }
  }
  const int title_height = int(8 * font / 0.55) + text_size(title_line, title_font, 2).height +
                           int(metric_lines.size()) * (text_size("Ag", font).height + int(12 * font / 0.55));

  const int margin_left = int(110 * font / 0.55), margin_bottom = int(70 * font / 0.55),
            margin_top = title_height + int(20 * font / 0.55), margin_right = int(150 * font / 0.55);
  const cv::Rect area(margin_left, margin_top, W - margin_left - margin_right, H - margin_top - margin_bottom);
  // Equal aspect: one metres-per-pixel for both axes, the data centred in the plot area.
  const double m_per_px = std::max((hi0 - lo0) / area.width, (hi1 - lo1) / area.height);
  const double c0 = 0.5 * (lo0 + hi0), c1 = 0.5 * (lo1 + hi1);
  lo0 = c0 - 0.5 * area.width * m_per_px, hi0 = c0 + 0.5 * area.width * m_per_px;
  lo1 = c1 - 0.5 * area.height * m_per_px, hi1 = c1 + 0.5 * area.height * m_per_px;
  auto to_px = [&](const Eigen::Vector3d& p) {
    const double x = area.x + (p[ax0] - lo0) / m_per_px, y = area.y + area.height - (p[ax1] - lo1) / m_per_px;
    return cv::Point(int(std::lround(x * kSub)), int(std::lround(y * kSub)));
  };
  auto polyline = [&](cv::Mat& img, const cv::Point& a, const cv::Point& b, const cv::Scalar& colour, int width) {
    cv::line(img, a, b, colour, width, cv::LINE_AA, kShift);
  };

  cv::Mat img(H, W, CV_8UC3, kWhite);

  // Grid and ticks (metres).
  const double step = nice_step(std::max(hi0 - lo0, hi1 - lo1) / 7.0);
  const int decimals = decimals_for(step);
  const int tick_len = 6;
  for (const double v : trajectory_plot_ticks(lo0, hi0, step)) {
    const int x = int(std::lround(area.x + (v - lo0) / m_per_px));
    cv::line(img, {x, area.y}, {x, area.y + area.height}, kGrid, 1);
    cv::line(img, {x, area.y + area.height}, {x, area.y + area.height + tick_len}, kAxis, 1);
    const std::string label = format(v, decimals);
    const cv::Size s = text_size(label, font);
    text(img, label, {x - s.width / 2, area.y + area.height + tick_len + 6 + s.height}, font, kBlack);
  }
  for (const double v : trajectory_plot_ticks(lo1, hi1, step)) {
    const int y = int(std::lround(area.y + area.height - (v - lo1) / m_per_px));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, kGrid, 1);
    cv::line(img, {area.x - tick_len, y}, {area.x, y}, kAxis, 1);
    const std::string label = format(v, decimals);
    const cv::Size s = text_size(label, font);
    text(img, label, {area.x - tick_len - 6 - s.width, y + s.height / 2}, font, kBlack);
  }
  cv::rectangle(img, area, kAxis, 1);
  {
    const std::string xlabel = std::string(axis_names[ax0]) + " [m]";
    const cv::Size s = text_size(xlabel, font * 1.1);
    text(img, xlabel, {area.x + area.width / 2 - s.width / 2, H - int(14 * font / 0.55)}, font * 1.1, kBlack);
    const std::string ylabel = std::string(axis_names[ax1]) + " [m]";
    const cv::Size t = text_size(ylabel, font * 1.1);
    cv::Mat label_img(t.height + 10, t.width + 4, CV_8UC3, kWhite);
    text(label_img, ylabel, {2, t.height + 2}, font * 1.1, kBlack);
    cv::rotate(label_img, label_img, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int lx = int(10 * font / 0.55), ly = area.y + area.height / 2 - label_img.rows / 2;
    label_img.copyTo(img(cv::Rect(lx, ly, label_img.cols, label_img.rows)));
  }

  // Data, clipped to the plot area.
  cv::Mat plot = img(area);
  const cv::Point offset(area.x * int(kSub), area.y * int(kSub));
  auto local = [&](const Eigen::Vector3d& p) { return to_px(p) - offset; };
  const int line_w = std::max(1, int(std::lround(2 * font / 0.55)));

  std::vector<cv::Point> data_px;  // whole-pixel image positions of everything drawn, for placing the legend
  for (const auto& p : gt_points) data_px.push_back(to_px(p) / int(kSub));
  for (const StampedPose& pose : aligned) data_px.push_back(to_px(pose.T_world_camera.translation()) / int(kSub));

  const ColourMap cmap;
  const double max_error = result.ate.error_m.max;
  const double colour_top = max_error > 0 ? max_error : 1e-3;
  auto colour_of = [&](double e) { return cmap(e / colour_top); };

  // Difference lines first (underneath), then the unassociated estimate, ground truth, coloured estimate.
  for (const AtePair& p : pairs) {
    polyline(plot, local(gt[p.gt_index].T_world_camera.translation()),
             local(aligned[p.est_index].T_world_camera.translation()), kLink, 1);
  }
  for (size_t k = 1; k < aligned.size(); ++k) {
    polyline(plot, local(aligned[k - 1].T_world_camera.translation()), local(aligned[k].T_world_camera.translation()),
             kUnmatched, 1);
  }
  for (size_t k = 1; k < gt_points.size(); ++k)
    polyline(plot, local(gt_points[k - 1]), local(gt_points[k]), kBlack, line_w);
  for (size_t k = 0; k < pairs.size(); ++k) {
    const cv::Point a = local(aligned[pairs[k].est_index].T_world_camera.translation());
    if (k + 1 < pairs.size()) {
      const cv::Point b = local(aligned[pairs[k + 1].est_index].T_world_camera.translation());
      polyline(plot, a, b, colour_of(0.5 * (pairs[k].error_m + pairs[k + 1].error_m)), line_w + 1);
    }
  }
  for (const AtePair& p : pairs) {
    cv::circle(plot, local(aligned[p.est_index].T_world_camera.translation()), int((line_w + 1) * kSub),
               colour_of(p.error_m), cv::FILLED, cv::LINE_AA, kShift);
  }
  // Start markers: squares on the first associated ground-truth and estimate poses.
  for (const Eigen::Vector3d& start :
       {gt_points.front(), aligned[pairs.front().est_index].T_world_camera.translation()}) {
    const cv::Point s = local(start);
    const int r = int(5 * kSub);
    cv::rectangle(plot, s - cv::Point(r, r), s + cv::Point(r, r), kBlack, 2, cv::LINE_AA, kShift);
  }

  // Colour bar with metre ticks.
  {
    const int bar_w = int(22 * font / 0.55), bar_x = area.x + area.width + int(30 * font / 0.55);
    const int bar_y = area.y + area.height / 8, bar_h = area.height * 3 / 4;
    for (int r = 0; r < bar_h; ++r) {
      const double t = 1.0 - double(r) / std::max(1, bar_h - 1);
      cv::line(img, {bar_x, bar_y + r}, {bar_x + bar_w - 1, bar_y + r}, cmap(t), 1);
    }
    cv::rectangle(img, cv::Rect(bar_x, bar_y, bar_w, bar_h), kAxis, 1);
    const double cstep = nice_step(colour_top / 5.0);
    const int cdec = decimals_for(cstep);
    for (const double v : trajectory_plot_ticks(0.0, colour_top * (1 + 1e-9), cstep)) {
      const int y = int(std::lround(bar_y + bar_h - 1 - v / colour_top * (bar_h - 1)));
      cv::line(img, {bar_x + bar_w, y}, {bar_x + bar_w + tick_len, y}, kAxis, 1);
      const std::string label = format(v, cdec);
      const cv::Size s = text_size(label, font);
      text(img, label, {bar_x + bar_w + tick_len + 4, y + s.height / 2}, font, kBlack);
    }
    const std::string heading = "ATE [m]";
    const cv::Size s = text_size(heading, font);
    text(img, heading, {bar_x + bar_w / 2 - s.width / 2, bar_y - int(12 * font / 0.55)}, font, kBlack);
  }

  // Title: the caller's line (bold, shrunk to fit) and the metrics, split over two lines when too wide.
  {
    const int y0 = int(8 * font / 0.55);
    const cv::Size s1 = text_size(title_line, title_font, 2);
    int y = y0 + s1.height;
    text(img, title_line, {std::max(4, W / 2 - s1.width / 2), y}, title_font, kBlack, 2);
    for (const std::string& line : metric_lines) {
      const cv::Size s2 = text_size(line, font);
      y += s2.height + int(12 * font / 0.55);
      text(img, line, {std::max(4, W / 2 - s2.width / 2), y}, font, kBlack);
    }
  }

  // Legend in the corner of the plot that hides the fewest drawn points; the "without ground truth" entry only when
  // such poses exist.
  {
    enum Kind { kGroundTruth, kEstimate, kUnmatchedPose, kDifference, kStart };
    std::vector<std::pair<Kind, std::string>> entries = {{kGroundTruth, "ground truth"},
                                                         {kEstimate, "aligned estimate (colour: ATE)"}};
    if (pairs.size() < est.size()) entries.push_back({kUnmatchedPose, "estimate without ground truth"});
    entries.push_back({kDifference, "ATE difference"});
    entries.push_back({kStart, "start"});
    int width = 0;
    const cv::Size ts = text_size("Ag", font);
    for (const auto& e : entries) width = std::max(width, text_size(e.second, font).width);
    const int rows = int(entries.size());
    const int row = ts.height + int(12 * font / 0.55), sample = int(36 * font / 0.55), pad_px = 8;
    const cv::Size box_size(pad_px * 3 + sample + width, pad_px * 2 + row * rows - 6);
    cv::Rect box;
    size_t fewest = SIZE_MAX;
    for (int corner = 0; corner < 4; ++corner) {  // upper left, upper right, lower left, lower right
      const int x = corner % 2 == 0 ? area.x + 10 : area.x + area.width - 10 - box_size.width;
      const int y = corner < 2 ? area.y + 10 : area.y + area.height - 10 - box_size.height;
      const cv::Rect candidate = cv::Rect(cv::Point(x, y), box_size) & cv::Rect(0, 0, W, H);
      size_t covered = 0;
      for (const cv::Point& p : data_px) covered += candidate.contains(p) ? 1 : 0;
      if (covered < fewest) {
        fewest = covered;
        box = candidate;
      }
    }
    cv::Mat roi = img(box);
    cv::Mat overlay(roi.size(), roi.type(), kWhite);
    cv::addWeighted(overlay, 0.85, roi, 0.15, 0.0, roi);
    cv::rectangle(img, box, kAxis, 1);
    for (int k = 0; k < rows; ++k) {
      const int y = box.y + pad_px + k * row + row / 2 - 3;
      const cv::Point a(box.x + pad_px, y), b(box.x + pad_px + sample, y);
      switch (entries[k].first) {
        case kGroundTruth:
          cv::line(img, a, b, kBlack, line_w, cv::LINE_AA);
          break;
        case kEstimate:
          for (int s = 0; s < 4; ++s) {
            cv::line(img, a + cv::Point(s * sample / 4, 0), a + cv::Point((s + 1) * sample / 4, 0), cmap(s / 3.0),
                     line_w + 1, cv::LINE_AA);
          }
          break;
        case kUnmatchedPose:
          cv::line(img, a, b, kUnmatched, 1, cv::LINE_AA);
          break;
        case kDifference:
          cv::line(img, a, b, kLink, 1, cv::LINE_AA);
          break;
        case kStart: {
          const cv::Point c((a.x + b.x) / 2, y);
          cv::rectangle(img, c - cv::Point(5, 5), c + cv::Point(5, 5), kBlack, 2, cv::LINE_AA);
          break;
        }
      }
      text(img, entries[k].second, {b.x + pad_px, y + ts.height / 2}, font, kBlack);
    }
  }

  ColorImage out(W, H);
  for (int y = 0; y < H; ++y) {
    const cv::Vec3b* row = img.ptr<cv::Vec3b>(y);
    for (int x = 0; x < W; ++x) out(x, y) = Rgb8{row[x][2], row[x][1], row[x][0]};
  }
  return out;
}

void write_trajectory_plot(const std::string& path, const Trajectory& gt, const Trajectory& est,
                           const EvalResult& result, const TrajectoryPlotOptions& options) {
  write_color_png(path, render_trajectory_plot(gt, est, result, options));  // atomic, errors name the file (io/image_io.h)
}

}  // namespace hf
