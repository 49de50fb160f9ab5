#include "head/render.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"

namespace hf::head {
namespace {

struct Projection {
  float scale = 1, x0 = 0, y0 = 0;
  Eigen::Vector3f to_pixel(const Eigen::Vector3f& v) const {  // v in the view frame
    return {(v.x() - x0) * scale, (y0 - v.y()) * scale, v.z()};
  }
};

Projection fit(const std::vector<Eigen::Vector3f>& view, int w, int h) {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(std::numeric_limits<float>::max()), hi = -lo;
  for (const auto& v : view) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  Projection p;
  if (view.empty()) return p;
  const float margin = 0.05f;
  const float sx = (hi.x() - lo.x()), sy = (hi.y() - lo.y());
  const float extent = std::max(std::max(sx / w, sy / h), 1e-30f);
  p.scale = (1.0f - 2 * margin) / extent;
  // Centre the box.
  p.x0 = 0.5f * (lo.x() + hi.x()) - 0.5f * w / p.scale;
  p.y0 = 0.5f * (lo.y() + hi.y()) + 0.5f * h / p.scale;
  return p;
}

}  // namespace

cv::Mat render_mesh(const TriangleMesh& mesh, const Eigen::Matrix3f& R_view_mesh, const std::vector<Rgb8>& colors,
                    const std::vector<RenderMarker>& markers, const RenderOptions& options) {
  const int W = std::max(options.width_px, 8), H = std::max(options.height_px, 8);
  cv::Mat image(H, W, CV_8UC3, cv::Scalar(options.background.b, options.background.g, options.background.r));
  std::vector<Eigen::Vector3f> view(mesh.vertices.size());
  for (size_t i = 0; i < view.size(); ++i) view[i] = R_view_mesh * mesh.vertices[i];
  const Projection proj = fit(view, W, H);
  std::vector<Eigen::Vector3f> px(view.size());
  for (size_t i = 0; i < view.size(); ++i) px[i] = proj.to_pixel(view[i]);
  std::vector<float> zbuf(static_cast<size_t>(W) * H, -std::numeric_limits<float>::infinity());
  const std::vector<Rgb8>& col = colors.size() == mesh.vertices.size()
                                     ? colors
                                     : (mesh.colors.size() == mesh.vertices.size() ? mesh.colors : colors);
  const bool have_colors = col.size() == mesh.vertices.size();
  const Eigen::Vector3f light = Eigen::Vector3f(0.3f, 0.4f, 1.0f).normalized();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3f &a = px[t[0]], &b = px[t[1]], &c = px[t[2]];
    const Eigen::Vector3f n = (view[t[1]] - view[t[0]]).cross(view[t[2]] - view[t[0]]);
    const float nn = n.norm();
    if (!(nn > 0)) continue;
    // Two-sided lighting: open meshes and inconsistent winding still read as surfaces.
    const float shade = 0.25f + 0.75f * std::abs(n.dot(light)) / nn;
    const float area = (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    if (std::abs(area) < 1e-12f) continue;
    const int x_lo = std::max(0, static_cast<int>(std::floor(std::min({a.x(), b.x(), c.x()}))));
    const int x_hi = std::min(W - 1, static_cast<int>(std::ceil(std::max({a.x(), b.x(), c.x()}))));
    const int y_lo = std::max(0, static_cast<int>(std::floor(std::min({a.y(), b.y(), c.y()}))));
    const int y_hi = std::min(H - 1, static_cast<int>(std::ceil(std::max({a.y(), b.y(), c.y()}))));
    for (int y = y_lo; y <= y_hi; ++y)
      for (int x = x_lo; x <= x_hi; ++x) {
        const float qx = x + 0.5f, qy = y + 0.5f;
        const float w0 = ((b.x() - qx) * (c.y() - qy) - (b.y() - qy) * (c.x() - qx)) / area;
        const float w1 = ((c.x() - qx) * (a.y() - qy) - (c.y() - qy) * (a.x() - qx)) / area;
        const float w2 = 1.0f - w0 - w1;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        const float z = w0 * a.z() + w1 * b.z() + w2 * c.z();
        float& zb = zbuf[static_cast<size_t>(y) * W + x];
        if (z <= zb) continue;
        zb = z;
        Eigen::Vector3f rgb(200, 200, 200);
        if (have_colors) {
          rgb = w0 * Eigen::Vector3f(col[t[0]].r, col[t[0]].g, col[t[0]].b) +
                w1 * Eigen::Vector3f(col[t[1]].r, col[t[1]].g, col[t[1]].b) +
                w2 * Eigen::Vector3f(col[t[2]].r, col[t[2]].g, col[t[2]].b);
        }
        rgb *= shade;
        image.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(rgb.z()), cv::saturate_cast<uchar>(rgb.y()),
                                              cv::saturate_cast<uchar>(rgb.x()));
      }
  }
  const int radius = std::max(3, W / 160);
  for (const RenderMarker& m : markers) {
    const Eigen::Vector3f p = proj.to_pixel(R_view_mesh * m.position);
    const int x = static_cast<int>(p.x()), y = static_cast<int>(p.y());
    if (x < 0 || y < 0 || x >= W || y >= H) continue;
    // Visible when no surface lies clearly in front (a few pixels' depth of tolerance).
    const float tolerance = 3.0f / proj.scale;
    const bool visible = zbuf[static_cast<size_t>(y) * W + x] <= p.z() + tolerance;
    const cv::Scalar color(m.color.b, m.color.g, m.color.r);
    cv::circle(image, {x, y}, radius, color, visible ? cv::FILLED : 1, cv::LINE_AA);
    if (!m.label.empty())
      cv::putText(image, m.label, {x + radius + 1, y - radius}, cv::FONT_HERSHEY_PLAIN, 0.8, color, 1, cv::LINE_AA);
  }
  return image;
}

cv::Mat render_views(const TriangleMesh& mesh, const std::vector<Eigen::Matrix3f>& R_view_mesh,
                     const std::vector<Rgb8>& colors, const std::vector<RenderMarker>& markers,
                     const RenderOptions& options) {
  std::vector<cv::Mat> tiles;
  for (const Eigen::Matrix3f& R : R_view_mesh) tiles.push_back(render_mesh(mesh, R, colors, markers, options));
  if (tiles.empty()) return {};
  cv::Mat out;
  cv::hconcat(tiles, out);
  return out;
}

namespace {

constexpr int kLegendFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kLegendScale = 0.5;
constexpr int kSwatch = 16, kPad = 8, kRow = 26;

int legend_text_width(const std::string& s) {
  int baseline = 0;
  return cv::getTextSize(s, kLegendFont, kLegendScale, 1, &baseline).width;
}

cv::Scalar bgr(Rgb8 c) { return cv::Scalar(c.b, c.g, c.r); }

// Lays the swatches out in rows across `width` from (x0, y0); draws them on `strip` when given. Returns the height
// used (0 for no entries).
int swatch_rows(cv::Mat* strip, const std::vector<LegendEntry>& entries, int width, int x0, int y0) {
  int x = x0, y = y0;
  for (const LegendEntry& e : entries) {
    const int w = kSwatch + 6 + legend_text_width(e.name) + 2 * kPad;
    if (x > x0 && x + w > width) x = x0, y += kRow;
    if (strip) {
      cv::rectangle(*strip, cv::Rect(x, y + 4, kSwatch, kSwatch), bgr(e.color), cv::FILLED);
      cv::rectangle(*strip, cv::Rect(x, y + 4, kSwatch, kSwatch), cv::Scalar(0, 0, 0), 1);
      cv::putText(*strip, e.name, cv::Point(x + kSwatch + 6, y + 17), kLegendFont, kLegendScale, cv::Scalar(0, 0, 0),
                  1, cv::LINE_AA);
    }
    x += w;
  }
  return entries.empty() ? 0 : y - y0 + kRow;
}

cv::Mat stacked(const cv::Mat& image, const cv::Mat& strip) {
  cv::Mat out;
  cv::vconcat(image, strip, out);
  return out;
}

std::string tick_label(double v, const std::string& unit) {
  char buffer[64];
  std::snprintf(buffer, sizeof buffer, "%.3g", v);
  return std::string(buffer) + (unit.empty() ? "" : " " + unit);
}

}  // namespace

cv::Mat with_swatch_legend(const cv::Mat& image, const std::vector<LegendEntry>& entries) {
  const int h = swatch_rows(nullptr, entries, image.cols, kPad, kPad) + 2 * kPad;
  cv::Mat strip(h, image.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  swatch_rows(&strip, entries, image.cols, kPad, kPad);
  return stacked(image, strip);
}

cv::Mat with_color_bar(const cv::Mat& image, double lo, double hi, Rgb8 (*map)(double value, double lo, double hi),
                       const std::string& caption, const std::string& unit, const std::vector<LegendEntry>& extra) {
  if (!(hi > lo)) hi = lo + 1.0;  // a constant field: any bar shows its one colour at lo
  const int W = image.cols;
  // caption row, bar, tick labels, then the extra swatches
  const int bar_x0 = kPad + legend_text_width(tick_label(lo, unit)) / 2;
  const int bar_x1 = W - kPad - legend_text_width(tick_label(hi, unit)) / 2;
  if (bar_x1 - bar_x0 < 40)
    throw Error("legend: an image of " + std::to_string(W) + " px is too narrow for a colour bar");
  const int caption_y = kPad + 14, bar_y = caption_y + 10, bar_h = 16, ticks_y = bar_y + bar_h + 20;
  const int extra_y = ticks_y + 6;
  const int h = extra_y + swatch_rows(nullptr, extra, W, kPad, extra_y) + kPad;
  cv::Mat strip(h, W, CV_8UC3, cv::Scalar(255, 255, 255));
  cv::putText(strip, caption, cv::Point(kPad, caption_y), kLegendFont, kLegendScale, cv::Scalar(0, 0, 0), 1,
              cv::LINE_AA);
  for (int x = bar_x0; x <= bar_x1; ++x) {
    const double v = lo + (hi - lo) * double(x - bar_x0) / double(bar_x1 - bar_x0);
    cv::line(strip, {x, bar_y}, {x, bar_y + bar_h - 1}, bgr(map(v, lo, hi)), 1);
  }
  // The frame one pixel outside the bar, so its end columns show the map's extremes.
  cv::rectangle(strip, cv::Rect(bar_x0 - 1, bar_y - 1, bar_x1 - bar_x0 + 3, bar_h + 2), cv::Scalar(0, 0, 0), 1);
  for (const double v : {lo, 0.5 * (lo + hi), hi}) {
    const int x = bar_x0 + int(std::lround((v - lo) / (hi - lo) * (bar_x1 - bar_x0)));
    cv::line(strip, {x, bar_y + bar_h}, {x, bar_y + bar_h + 4}, cv::Scalar(0, 0, 0), 1);
    const std::string label = tick_label(v, unit);
    cv::putText(strip, label, cv::Point(x - legend_text_width(label) / 2, ticks_y), kLegendFont, kLegendScale,
                cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  swatch_rows(&strip, extra, W, kPad, extra_y);
  return stacked(image, strip);
}

void write_png(const std::string& path, const cv::Mat& image) {
  write_path_atomically(path, [&](const std::string& tmp) {
    if (!cv::imwrite(tmp, image)) throw Error(path + ": cannot write the PNG");
  });
}

}  // namespace hf::head
