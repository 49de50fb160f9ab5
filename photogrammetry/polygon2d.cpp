#include "photogrammetry/polygon2d.h"

#include <algorithm>
#include <cmath>

namespace hf::photogrammetry {
namespace {

double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

int orientation(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c) {
  const double v = cross(b - a, c - a);
  const double scale = (b - a).norm() * (c - a).norm();
  if (std::fabs(v) <= 1e-12 * scale) return 0;
  return v > 0 ? 1 : -1;
}

bool on_segment(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& p) {
  return p.x() >= std::min(a.x(), b.x()) && p.x() <= std::max(a.x(), b.x()) && p.y() >= std::min(a.y(), b.y()) &&
         p.y() <= std::max(a.y(), b.y());
}

bool segments_touch(const Eigen::Vector2d& p1, const Eigen::Vector2d& p2, const Eigen::Vector2d& q1,
                    const Eigen::Vector2d& q2) {
  const int o1 = orientation(p1, p2, q1), o2 = orientation(p1, p2, q2);
  const int o3 = orientation(q1, q2, p1), o4 = orientation(q1, q2, p2);
  if (o1 != o2 && o3 != o4 && o1 != 0 && o2 != 0 && o3 != 0 && o4 != 0) return true;
  return (o1 == 0 && on_segment(p1, p2, q1)) || (o2 == 0 && on_segment(p1, p2, q2)) ||
         (o3 == 0 && on_segment(q1, q2, p1)) || (o4 == 0 && on_segment(q1, q2, p2));
}

}  // namespace

double signed_area(const Polygon2d& p) {
  double a = 0;
  for (size_t i = 0, n = p.size(); i < n; ++i) a += cross(p[i], p[(i + 1) % n]);
  return 0.5 * a;
}

bool point_in_polygon(const Polygon2d& poly, const Eigen::Vector2d& p) {
  bool inside = false;
  for (size_t i = 0, n = poly.size(), j = n - 1; i < n; j = i++) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
      inside = !inside;
  }
  return inside;
}

bool self_intersecting(const Polygon2d& p) {
  const size_t n = p.size();
  if (n < 3) return true;
  for (size_t i = 0; i < n; ++i)
    if ((p[i] - p[(i + 1) % n]).norm() == 0) return true;
  for (size_t i = 0; i < n; ++i) {
    const Eigen::Vector2d& a0 = p[i];
    const Eigen::Vector2d& a1 = p[(i + 1) % n];
    for (size_t j = i + 1; j < n; ++j) {
      const Eigen::Vector2d& b0 = p[j];
      const Eigen::Vector2d& b1 = p[(j + 1) % n];
      const bool adjacent = j == i + 1 || (i == 0 && j == n - 1);
      if (adjacent) {
        // Adjacent edges share one vertex; they intersect elsewhere only when they fold back collinearly.
        const Eigen::Vector2d shared = j == i + 1 ? a1 : a0;
        const Eigen::Vector2d u = (j == i + 1 ? a0 : a1) - shared, v = (j == i + 1 ? b1 : b0) - shared;
        if (orientation(shared, shared + u, shared + v) == 0 && u.dot(v) > 0) return true;
        continue;
      }
      if (segments_touch(a0, a1, b0, b1)) return true;
    }
  }
  return false;
}

bool intersect_lines(const Eigen::Vector2d& a0, const Eigen::Vector2d& a1, const Eigen::Vector2d& b0,
                     const Eigen::Vector2d& b1, Eigen::Vector2d* out) {
  const Eigen::Vector2d r = a1 - a0, s = b1 - b0;
  const double denom = cross(r, s);
  if (!(std::fabs(denom) > 1e-9 * r.norm() * s.norm())) return false;
  const double t = cross(b0 - a0, s) / denom;
  *out = a0 + t * r;
  return out->allFinite();
}

}  // namespace hf::photogrammetry
