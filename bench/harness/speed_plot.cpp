#include "bench/harness/speed_plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "bench/harness/results.h"
#include "core/error.h"
#include "io/image_io.h"

namespace hf::bench {
namespace {

const cv::Scalar kWhite(255, 255, 255), kBlack(0, 0, 0), kGrid(232, 232, 232), kAxis(90, 90, 90),
    kFront(50, 50, 50);  // dark grey front line and rings
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
// The largest time (ms) or error (m) drawn: far beyond any real run, far below where ranges and logarithms overflow.
constexpr double kMaxSpeedPlotValue = 1e12;

// Distinct colours (BGR), after Tableau 10.
const cv::Scalar kPalette[] = {{180, 119, 31}, {14, 127, 255}, {44, 160, 44},  {40, 39, 214},  {189, 103, 148},
                               {75, 86, 140},  {194, 119, 227}, {127, 127, 127}, {34, 189, 188}, {207, 190, 23}};

void text(cv::Mat& img, const std::string& s, cv::Point origin, double scale, const cv::Scalar& colour,
          int thickness = 1) {
  cv::putText(img, s, origin, kFont, scale, colour, thickness, cv::LINE_AA);
}

cv::Size text_size(const std::string& s, double scale, int thickness = 1) {
  int baseline = 0;
  return cv::getTextSize(s, kFont, scale, thickness, &baseline);
}

// `s` broken at spaces into lines each at most `width` pixels wide at this scale (a single word wider than that
// is cut character by character), so no footer runs off the canvas however many methods it lists.
std::vector<std::string> wrap_to_width(const std::string& s, double scale, int width) {
  std::vector<std::string> lines;
  std::string line;
  size_t i = 0;
  while (i < s.size()) {
    const size_t space = s.find(' ', i);
    const std::string word = s.substr(i, space == std::string::npos ? std::string::npos : space + 1 - i);
    i = space == std::string::npos ? s.size() : space + 1;
    if (text_size(line + word, scale).width <= width || line.empty()) {
      line += word;
    } else {
      lines.push_back(line);
      line = word;
    }
    while (line.size() > 1 && text_size(line, scale).width > width) {  // one word wider than the canvas
      size_t n = line.size() - 1;
      while (n > 1 && text_size(line.substr(0, n), scale).width > width) --n;
      lines.push_back(line.substr(0, n));
      line = line.substr(n);
    }
  }
  if (!line.empty()) lines.push_back(line);
  return lines;
}

std::string format_g(double v) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%g", v);
  return buffer;
}

double nice_step(double raw) {
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * p >= raw * (1 - 1e-9)) return m * p;
  }
  return 10.0 * p;
}

// One axis: data range -> [0, 1], linear or logarithmic, with tick values.
struct Axis {
  bool log = false;
  double lo = 0.0, hi = 1.0;  // in data units (log: > 0)

  static Axis fit(std::vector<double> values) {
    Axis a;
    values.erase(std::remove_if(values.begin(), values.end(), [](double v) { return !std::isfinite(v); }),
                 values.end());
    if (values.empty()) return a;
    const auto [mn, mx] = std::minmax_element(values.begin(), values.end());
    double lo = *mn, hi = *mx;
    if (lo > 0.0 && hi / lo > 10.0) {
      a.log = true;
      a.lo = lo / 1.4;
      a.hi = hi * 1.4;
      return a;
    }
    if (hi - lo < 1e-12 * std::max(1.0, std::abs(hi))) {
      const double d = hi != 0.0 ? 0.2 * std::abs(hi) : 1.0;
      lo -= d, hi += d;
    } else {
      const double pad = 0.1 * (hi - lo);
      lo -= pad, hi += pad;
    }
    if (*mn >= 0.0) lo = std::max(lo, 0.0);  // times and errors are never negative
    a.lo = lo, a.hi = hi;
    return a;
  }
  double unit(double v) const {
    if (log) return (std::log(v) - std::log(lo)) / (std::log(hi) - std::log(lo));
    return (v - lo) / (hi - lo);
  }
  std::vector<double> ticks() const {
    std::vector<double> t;
    if (log) {
      const int k0 = int(std::floor(std::log10(lo))), k1 = int(std::ceil(std::log10(hi)));
      const bool few = k1 - k0 <= 3;
      for (int k = k0; k <= k1; ++k) {
        for (double m : few ? std::vector<double>{1, 2, 5} : std::vector<double>{1}) {
          const double v = m * std::pow(10.0, k);
          if (v >= lo && v <= hi) t.push_back(v);
        }
      }
      return t;
    }
    // From a count, never "v <= hi; v += step": that loop spins when hi is inf or v + step == v.
    const double step = nice_step((hi - lo) / 6.0);
    const double first = std::ceil(lo / step), last = std::floor(hi * (1 + 1e-12) / step);
    if (!(std::isfinite(first) && std::isfinite(last)) || last < first) return t;
    for (int k = 0; k < int(std::min(last - first + 1.0, 1000.0)); ++k) {
      const double v = (first + k) * step;
      t.push_back(std::abs(v) < 1e-12 * step ? 0.0 : v);
    }
    return t;
  }
};

void dashed_line(cv::Mat& img, cv::Point2d a, cv::Point2d b, const cv::Scalar& colour, int width) {
  const double length = cv::norm(b - a), dash = 9.0, gap = 6.0;
  if (!(length >= 1e-9 && length <= 1e7)) return;  // a NaN or absurd length would make the dash count undefined
  const cv::Point2d dir = (b - a) / length;
  const int dashes = int(std::min(std::ceil(length / (dash + gap)), 100000.0));  // a count, not s += dash + gap
  for (int k = 0; k < dashes; ++k) {
    const double s = k * (dash + gap);
    const cv::Point2d p = a + dir * s, q = a + dir * std::min(length, s + dash);
    cv::line(img, cv::Point(int(std::lround(p.x)), int(std::lround(p.y))),
             cv::Point(int(std::lround(q.x)), int(std::lround(q.y))), colour, width, cv::LINE_AA);
  }
}

}  // namespace

ColorImage render_speed_plot(const std::vector<SpeedPoint>& points, const SpeedPlotOptions& options) {
  if (options.width_px < 400 || options.height_px < 300 || options.width_px > 8000 || options.height_px > 8000) {
    throw Error("speed plot: size must be within 400x300 .. 8000x8000 px, got " + std::to_string(options.width_px) +
                "x" + std::to_string(options.height_px));
  }
  std::vector<SpeedPoint> pts;
  std::vector<std::string> not_plotted = options.not_plotted;
  for (const SpeedPoint& p : points) {
    // Beyond kMaxSpeedPlotValue the axis ranges (padded by x1.4) overflow: such a point is listed, not drawn.
    if (std::isfinite(p.ms_per_frame) && std::isfinite(p.ate_m) && p.ms_per_frame > 0.0 && p.ate_m >= 0.0 &&
        p.ms_per_frame <= kMaxSpeedPlotValue && p.ate_m <= kMaxSpeedPlotValue) {
      pts.push_back(p);
    } else {
      not_plotted.push_back(p.label);
    }
  }
  const int W = options.width_px, H = options.height_px;
  const double font = std::clamp(std::min(H / 1450.0, W / 2000.0), 0.35, 1.2);
  const int u = std::max(1, int(std::lround(font / 0.55)));  // line-width unit

  std::vector<double> xs, ys;
  for (const SpeedPoint& p : pts) xs.push_back(p.ms_per_frame), ys.push_back(p.ate_m);
  const Axis ax = Axis::fit(xs), ay = Axis::fit(ys);

  const std::string title = options.title.empty() ? "speed against error" : options.title;
  const int title_h = text_size(title, font * 1.25, 2).height, line_h = text_size("Ag", font).height;
  const int margin_top = int(20 * font / 0.55) + title_h + (options.subtitle.empty() ? 0 : line_h + 12);
  const int margin_left = int(110 * font / 0.55), margin_right = int(40 * font / 0.55);
  // The footer, wrapped to the width from the plot's left edge to the canvas's right margin; the plot area gives
  // up the height its lines take.
  std::vector<std::string> footer = wrap_to_width(
      "disc: hashfusion method   square: peer (PCL, Open3D; frame-to-frame)   ringed, dashed: Pareto front "
      "(lower left is better)",
      font * 0.9, W - margin_left - margin_right);
  if (!not_plotted.empty()) {
    std::string line = "not plotted (failed or lost): ";
    for (size_t k = 0; k < not_plotted.size(); ++k) line += (k ? ", " : "") + not_plotted[k];
    for (std::string& l : wrap_to_width(line, font * 0.9, W - margin_left - margin_right)) footer.push_back(l);
  }
  // At most a third of the canvas: beyond that the list is cut with a count of what is left out.
  const int max_footer_lines = std::max(2, (H / 3) / (line_h + 12));
  if (int(footer.size()) > max_footer_lines) {
    const size_t cut = footer.size() - size_t(max_footer_lines) + 1;
    footer.resize(size_t(max_footer_lines) - 1);
    footer.push_back("... and " + std::to_string(cut) + " more lines of methods not plotted");
  }
  const int footer_lines = int(footer.size());
  const int margin_bottom = int(75 * font / 0.55) + footer_lines * (line_h + 12);
  const cv::Rect area(margin_left, margin_top, W - margin_left - margin_right, H - margin_top - margin_bottom);
  auto to_px = [&](double x, double y) {
    return cv::Point2d(area.x + ax.unit(x) * area.width, area.y + area.height - ay.unit(y) * area.height);
  };

  cv::Mat img(H, W, CV_8UC3, kWhite);
  const int tick_len = 6;
  for (double v : ax.ticks()) {
    const int x = int(std::lround(to_px(v, ay.lo).x));
    cv::line(img, {x, area.y}, {x, area.y + area.height}, kGrid, 1);
    cv::line(img, {x, area.y + area.height}, {x, area.y + area.height + tick_len}, kAxis, 1);
    const std::string label = format_g(v);
    const cv::Size s = text_size(label, font);
    text(img, label, {x - s.width / 2, area.y + area.height + tick_len + 6 + s.height}, font, kBlack);
  }
  for (double v : ay.ticks()) {
    const int y = int(std::lround(to_px(ax.lo, v).y));
    cv::line(img, {area.x, y}, {area.x + area.width, y}, kGrid, 1);
    cv::line(img, {area.x - tick_len, y}, {area.x, y}, kAxis, 1);
    const std::string label = format_g(v);
    const cv::Size s = text_size(label, font);
    text(img, label, {area.x - tick_len - 6 - s.width, y + s.height / 2}, font, kBlack);
  }
  cv::rectangle(img, area, kAxis, 1);
  {
    const std::string xlabel = std::string("ms per frame") + (ax.log ? " (log scale)" : "");
    const cv::Size s = text_size(xlabel, font * 1.1);
    text(img, xlabel, {area.x + area.width / 2 - s.width / 2, area.y + area.height + tick_len + 2 * s.height + 22},
         font * 1.1, kBlack);
    const std::string ylabel = std::string("ATE RMSE [m]") + (ay.log ? " (log scale)" : "");
    const cv::Size t = text_size(ylabel, font * 1.1);
    cv::Mat label_img(t.height + 10, t.width + 4, CV_8UC3, kWhite);
    text(label_img, ylabel, {2, t.height + 2}, font * 1.1, kBlack);
    cv::rotate(label_img, label_img, cv::ROTATE_90_COUNTERCLOCKWISE);
    const int lx = int(8 * font / 0.55), ly = std::max(0, area.y + area.height / 2 - label_img.rows / 2);
    if (ly + label_img.rows <= H) label_img.copyTo(img(cv::Rect(lx, ly, label_img.cols, label_img.rows)));
  }

  // Pareto front: a dashed staircase (the region it bounds is attainable), its points ringed.
  std::vector<ParetoPoint> pp;
  for (const SpeedPoint& p : pts) pp.push_back({p.ms_per_frame, p.ate_m});
  const std::vector<size_t> front = pareto_front(pp);
  cv::Mat plot = img(area);
  const cv::Point2d origin(area.x, area.y);
  for (size_t k = 0; k + 1 < front.size(); ++k) {
    const cv::Point2d a = to_px(pts[front[k]].ms_per_frame, pts[front[k]].ate_m) - origin;
    const cv::Point2d b = to_px(pts[front[k + 1]].ms_per_frame, pts[front[k + 1]].ate_m) - origin;
    dashed_line(plot, a, {b.x, a.y}, kFront, 2 * u);
    dashed_line(plot, {b.x, a.y}, b, kFront, 2 * u);
  }
  const int r = 6 * u;
  std::vector<cv::Rect> taken;
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d c = to_px(pts[i].ms_per_frame, pts[i].ate_m);
    const cv::Point ci(int(std::lround(c.x)), int(std::lround(c.y)));
    taken.push_back(cv::Rect(ci.x - r, ci.y - r, 2 * r, 2 * r));
  }
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d c = to_px(pts[i].ms_per_frame, pts[i].ate_m) - origin;
    const cv::Point ci(int(std::lround(c.x)), int(std::lround(c.y)));
    const cv::Scalar colour = kPalette[i % (sizeof kPalette / sizeof kPalette[0])];
    if (pts[i].peer) {
      cv::rectangle(plot, ci - cv::Point(r, r), ci + cv::Point(r, r), colour, cv::FILLED, cv::LINE_AA);
    } else {
      cv::circle(plot, ci, r, colour, cv::FILLED, cv::LINE_AA);
    }
    if (std::find(front.begin(), front.end(), i) != front.end()) {
      cv::circle(plot, ci, r + 5 * u, kFront, 2 * u, cv::LINE_AA);
    }
  }
  // Labels beside their points, at the first of eight places that overlaps no point or earlier label.
  for (size_t i = 0; i < pts.size(); ++i) {
    const cv::Point2d c = to_px(pts[i].ms_per_frame, pts[i].ate_m);
    const cv::Point ci(int(std::lround(c.x)), int(std::lround(c.y)));
    const std::string& label = pts[i].label;
    const cv::Size s = text_size(label, font);
    const int d = r + 8 * u;
    const cv::Point offsets[] = {{d, -d},      {d, d + s.height},           {-d - s.width, -d},
                                 {-d - s.width, d + s.height}, {d, s.height / 2}, {-d - s.width, s.height / 2},
                                 {-s.width / 2, -d - 4},       {-s.width / 2, d + s.height + 4}};
    cv::Rect best;
    bool placed = false;
    for (const cv::Point& o : offsets) {
      const cv::Rect rect(ci.x + o.x, ci.y + o.y - s.height, s.width, s.height + 4);
      if ((rect & area) != rect) continue;
      bool overlaps = false;
      for (const cv::Rect& t : taken) overlaps = overlaps || (rect & t).area() > 0;
      if (!overlaps) {
        best = rect;
        placed = true;
        break;
      }
    }
    if (!placed) best = cv::Rect(ci.x + d, ci.y - d - s.height, s.width, s.height + 4);
    taken.push_back(best);
    text(img, label, {best.x, best.y + s.height}, font, kBlack);
  }

  // Title, subtitle and footer.
  {
    int y = int(10 * font / 0.55) + title_h;
    const cv::Size st = text_size(title, font * 1.25, 2);
    text(img, title, {std::max(4, W / 2 - st.width / 2), y}, font * 1.25, kBlack, 2);
    if (!options.subtitle.empty()) {
      y += line_h + 12;
      const cv::Size ss = text_size(options.subtitle, font);
      text(img, options.subtitle, {std::max(4, W / 2 - ss.width / 2), y}, font, kBlack);
    }
    int fy = H - int(12 * font / 0.55) - (footer_lines - 1) * (line_h + 12);
    for (const std::string& line : footer) {
      text(img, line, {area.x, fy}, font * 0.9, kAxis);
      fy += line_h + 12;
    }
  }
  if (pts.empty()) {
    const std::string msg = "no method has an ATE here";
    const cv::Size s = text_size(msg, font * 1.2);
    text(img, msg, {area.x + area.width / 2 - s.width / 2, area.y + area.height / 2}, font * 1.2, kAxis);
  }

  ColorImage out(W, H);
  for (int y = 0; y < H; ++y) {
    const cv::Vec3b* row = img.ptr<cv::Vec3b>(y);
    for (int x = 0; x < W; ++x) out(x, y) = Rgb8{row[x][2], row[x][1], row[x][0]};
  }
  return out;
}

void write_speed_plot(const std::string& path, const std::vector<SpeedPoint>& points,
                      const SpeedPlotOptions& options) {
  write_color_png(path, render_speed_plot(points, options));  // atomic, errors name the file (io/image_io.h)
}

}  // namespace hf::bench
