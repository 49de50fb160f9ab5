#include "photogrammetry/polygon_transfer.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

#include "photogrammetry/single_shot_sketching.h"

namespace hf::photogrammetry {

std::vector<double> edge_histogram(const ColorImage& image, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                   double strip_px, int bins, int side) {
  bins = std::clamp(bins, 1, 16);
  std::vector<double> h(size_t(bins * bins * bins), 0.0);
  const double length = (b - a).norm();
  if (!(length > 0) || image.empty()) return h;
  const Eigen::Vector2d u = (b - a) / length, n(-u.y(), u.x());
  const int steps = std::min(100000, int(std::ceil(length)));
  const int across = std::min(50, int(std::ceil(strip_px)));
  double count = 0;
  for (int i = 0; i <= steps; ++i)
    for (int j = side > 0 ? 1 : -across; j <= (side < 0 ? -1 : across); ++j) {
      const Eigen::Vector2d p = a + (length * i / std::max(1, steps)) * u + double(j) * n;
      const int x = int(std::lround(p.x())), y = int(std::lround(p.y()));
      if (x < 0 || y < 0 || x >= image.width() || y >= image.height()) continue;
      const Rgb8 c = image(x, y);
      const int r = c.r * bins / 256, g = c.g * bins / 256, bl = c.b * bins / 256;
      h[size_t((r * bins + g) * bins + bl)] += 1;
      count += 1;
    }
  if (count > 0)
    for (double& v : h) v /= count;
  return h;
}

namespace {

double intersection(const std::vector<double>& a, const std::vector<double>& b) {
  double s = 0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i) s += std::min(a[i], b[i]);
  return s;
}

// The two sides of a -> b: left (+normal) and right.
struct SideHistograms {
  std::vector<double> left, right;
};
SideHistograms side_histograms(const ColorImage& image, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                               const TransferOptions& o) {
  return {edge_histogram(image, a, b, o.strip_px, o.bins_per_channel, +1),
          edge_histogram(image, a, b, o.strip_px, o.bins_per_channel, -1)};
}

}  // namespace

std::optional<TransferResult> transfer_polygon(const Shot& source, const ColorImage& source_image,
                                               const Polygon2d& outline, const Eigen::Vector4d& plane,
                                               const Shot& target, const ColorImage& target_image,
                                               const std::vector<LineSegment2>& lines, const TransferOptions& o) {
  const auto points = back_project_onto_plane(source, outline, plane);
  if (!points) return std::nullopt;
  TransferResult r;
  for (const auto& X : *points) {
    const auto uv = target.project(X);
    if (!uv) return std::nullopt;
    r.projected.push_back(*uv);
  }
  const size_t n = outline.size();
  // Per edge, its best line: similarity, perpendicular offset, the edge's unit normal.
  struct Best {
    double similarity = 0, offset = 0;
    Eigen::Vector2d normal = Eigen::Vector2d::Zero();
  };
  struct Candidate {
    double similarity, offset;
  };
  std::vector<Best> best(n);
  for (size_t k = 0; k < n; ++k) {
    const Eigen::Vector2d p0 = r.projected[k], p1 = r.projected[(k + 1) % n];
    const double le = (p1 - p0).norm();
    if (!(le > 0)) continue;
    const Eigen::Vector2d u = (p1 - p0) / le, nrm(-u.y(), u.x());
    best[k].normal = nrm;
    std::vector<Candidate> candidates;
    // Sides matter: a window's bottom edge (glass above, wall below) must not match the top edge of the window
    // under it (wall above, glass below).
    const SideHistograms source_h = side_histograms(source_image, outline[k], outline[(k + 1) % n], o);
    for (size_t i = 0; i < lines.size(); ++i) {
      const Eigen::Vector2d d = lines[i].b - lines[i].a;
      if (d.norm() < o.snapping.min_segment_px) continue;
      const double angle = std::atan2(std::fabs(u.x() * d.y() - u.y() * d.x()), std::fabs(u.dot(d))) * 180 / M_PI;
      if (angle > o.max_angle_deg) continue;
      const double offset = nrm.dot(0.5 * (lines[i].a + lines[i].b) - p0);
      if (std::fabs(offset) > o.search_px) continue;
      const double ta = u.dot(lines[i].a - p0), tb = u.dot(lines[i].b - p0);
      if (std::max(ta, tb) <= -o.search_px || std::min(ta, tb) >= le + o.search_px) continue;
      // The line oriented like the edge, so its left side is the edge's left side.
      const bool along = d.dot(u) >= 0;
      const SideHistograms line_h =
          side_histograms(target_image, along ? lines[i].a : lines[i].b, along ? lines[i].b : lines[i].a, o);
      const double sim = 0.5 * (intersection(source_h.left, line_h.left) + intersection(source_h.right, line_h.right));
      if (sim >= o.min_similarity) candidates.push_back({sim, offset});
    }
    // Lines of equal quality (identical windows, the two sides of one) go to the nearest: the hypothesis plane is
    // the best guess of where the object is.
    double top = 0;
    for (const Candidate& c : candidates) top = std::max(top, c.similarity);
    for (const Candidate& c : candidates)
      if (c.similarity >= top - o.equal_similarity &&
          (best[k].similarity == 0 || std::fabs(c.offset) < std::fabs(best[k].offset))) {
        best[k].similarity = c.similarity;
        best[k].offset = c.offset;
      }
  }
  // The best pair anchors the outline across its edge; the best pair on an edge at least 30 degrees from it (the
  // next edge "added stepwise") fixes the other direction: the shift t solves n_a . t = o_a, n_b . t = o_b.
  int a = -1, b = -1;
  for (size_t k = 0; k < n; ++k)
    if (best[k].similarity > 0 && (a < 0 || best[k].similarity > best[size_t(a)].similarity)) a = int(k);
  Eigen::Vector2d shift = Eigen::Vector2d::Zero();
  if (a >= 0) {
    r.anchor_edge = a;
    r.anchor_similarity = best[size_t(a)].similarity;
    const Eigen::Vector2d na = best[size_t(a)].normal;
    for (size_t k = 0; k < n; ++k)
      if (best[k].similarity > 0 && std::fabs(na.x() * best[k].normal.y() - na.y() * best[k].normal.x()) > 0.5 &&
          (b < 0 || best[k].similarity > best[size_t(b)].similarity))
        b = int(k);
    shift = best[size_t(a)].offset * na;
    if (b >= 0) {
      Eigen::Matrix2d N;
      N.row(0) = na.transpose();
      N.row(1) = best[size_t(b)].normal.transpose();
      const Eigen::Vector2d t = N.inverse() * Eigen::Vector2d(best[size_t(a)].offset, best[size_t(b)].offset);
      if (t.allFinite()) shift = t;
    }
  }
  Polygon2d moved = r.projected;
  for (auto& p : moved) p += shift;
  r.points = snap_polygon(moved, lines, o.snapping).points;
  return r;
}

}  // namespace hf::photogrammetry
