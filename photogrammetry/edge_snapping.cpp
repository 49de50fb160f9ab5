#include "photogrammetry/edge_snapping.h"

#include <Eigen/Eigenvalues>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace hf::photogrammetry {

std::vector<LineSegment2> detect_line_segments(const ColorImage& image) {
  std::vector<LineSegment2> out;
  if (image.empty()) return out;
  cv::Mat grey(image.height(), image.width(), CV_8U);
  for (int v = 0; v < image.height(); ++v)
    for (int u = 0; u < image.width(); ++u) {
      const Rgb8 c = image(u, v);
      grey.at<std::uint8_t>(v, u) = std::uint8_t(std::lround(0.299 * c.r + 0.587 * c.g + 0.114 * c.b));
    }
  const cv::Ptr<cv::LineSegmentDetector> lsd = cv::createLineSegmentDetector(cv::LSD_REFINE_STD);
  std::vector<cv::Vec4f> lines;
  lsd->detect(grey, lines);
  for (const cv::Vec4f& l : lines) out.push_back({{l[0], l[1]}, {l[2], l[3]}});
  return out;
}

namespace {

// Whether segment s matches the edge p0 -> p1.
bool matches(const LineSegment2& s, const Eigen::Vector2d& p0, const Eigen::Vector2d& p1, const SnapOptions& o) {
  const Eigen::Vector2d e = p1 - p0, d = s.b - s.a;
  const double le = e.norm(), ld = d.norm();
  if (!(le > 0) || !(ld >= o.min_segment_px)) return false;
  const Eigen::Vector2d u = e / le, n(-u.y(), u.x());
  const double angle = std::atan2(std::fabs(u.x() * d.y() - u.y() * d.x()), std::fabs(u.dot(d))) * 180.0 / M_PI;
  if (angle > o.max_angle_deg) return false;
  if (std::fabs(n.dot(s.a - p0)) > o.max_distance_px || std::fabs(n.dot(s.b - p0)) > o.max_distance_px) return false;
  const double ta = u.dot(s.a - p0), tb = u.dot(s.b - p0);
  return std::max(ta, tb) > 0 && std::min(ta, tb) < le;  // overlaps the edge along it
}

// The length-weighted total-least-squares line through the matched segments' end points.
bool merged_line(const std::vector<LineSegment2>& lines, const std::vector<int>& ids, Eigen::Vector2d* p0,
                 Eigen::Vector2d* p1) {
  double w_sum = 0;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const int i : ids) {
    const double w = (lines[size_t(i)].b - lines[size_t(i)].a).norm();
    mean += w * (lines[size_t(i)].a + lines[size_t(i)].b);
    w_sum += 2 * w;
  }
  if (!(w_sum > 0)) return false;
  mean /= w_sum;
  Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
  for (const int i : ids) {
    const double w = (lines[size_t(i)].b - lines[size_t(i)].a).norm();
    for (const Eigen::Vector2d& p : {lines[size_t(i)].a, lines[size_t(i)].b})
      scatter += w * (p - mean) * (p - mean).transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(scatter);
  const Eigen::Vector2d dir = eig.eigenvectors().col(1);
  if (!dir.allFinite() || !(dir.norm() > 0)) return false;
  *p0 = mean;
  *p1 = mean + dir;
  return true;
}

}  // namespace

SnapResult snap_polygon(const Polygon2d& sketch, const std::vector<LineSegment2>& lines, const SnapOptions& o) {
  SnapResult r;
  r.points = sketch;
  const size_t n = sketch.size();
  bool any = false;
  for (size_t k = 0; k < n; ++k) {
    EdgeSnap e;
    e.p0 = sketch[k];
    e.p1 = sketch[(k + 1) % n];
    for (size_t i = 0; i < lines.size(); ++i)
      if (matches(lines[i], sketch[k], sketch[(k + 1) % n], o)) e.lines.push_back(int(i));
    if (!e.lines.empty() && !merged_line(lines, e.lines, &e.p0, &e.p1)) {
      e.lines.clear();
      e.p0 = sketch[k];
      e.p1 = sketch[(k + 1) % n];
    }
    any = any || !e.lines.empty();
    r.edges.push_back(e);
  }
  if (!any) return r;
  Polygon2d snapped = sketch;
  for (size_t k = 0; k < n; ++k) {
    const EdgeSnap& before = r.edges[(k + n - 1) % n];
    const EdgeSnap& after = r.edges[k];
    if (before.lines.empty() && after.lines.empty()) continue;
    Eigen::Vector2d x;
    if (intersect_lines(before.p0, before.p1, after.p0, after.p1, &x) && (x - sketch[k]).norm() <= o.max_vertex_move_px)
      snapped[k] = x;
  }
  if (self_intersecting(snapped)) return r;
  r.points = snapped;
  r.snapped = true;
  return r;
}

}  // namespace hf::photogrammetry
