#include "photogrammetry/single_shot_sketching.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>

namespace hf::photogrammetry {
namespace {

// The polygon's raster: bounding box scaled to at most max_px on its longer side.
struct Raster {
  Eigen::Vector2d origin;
  double scale = 1.0;  // raster cells per pixel
  cv::Mat mask;        // CV_8U, 255 inside the polygon
};

Raster rasterise(const Polygon2d& polygon, int max_px) {
  Eigen::Vector2d lo = polygon[0], hi = polygon[0];
  for (const auto& p : polygon) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  Raster r;
  r.origin = lo;
  const double extent = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1.0});
  r.scale = std::min(1.0, double(max_px) / extent);
  const int w = std::max(1, int(std::ceil((hi.x() - lo.x()) * r.scale)) + 1);
  const int h = std::max(1, int(std::ceil((hi.y() - lo.y()) * r.scale)) + 1);
  r.mask = cv::Mat::zeros(h, w, CV_8U);
  std::vector<cv::Point> pts;
  // fillPoly's fixed-point shift keeps sub-cell vertex positions (4 bits).
  for (const auto& p : polygon) {
    const Eigen::Vector2d q = (p - lo) * r.scale * 16.0;
    pts.emplace_back(int(std::lround(q.x())), int(std::lround(q.y())));
  }
  const cv::Point* contours[] = {pts.data()};
  const int counts[] = {int(pts.size())};
  cv::fillPoly(r.mask, contours, counts, 1, cv::Scalar(255), cv::LINE_8, 4);
  return r;
}

}  // namespace

std::vector<SegmentFit> fit_segments(const Shot& shot, int shot_index, const Polygon2d& polygon, const Cloud& cloud,
                                     const std::vector<PlaneSegment>& segments, const CloudFitOptions& options) {
  std::vector<SegmentFit> fits;
  const Raster raster = rasterise(polygon, std::max(8, options.raster_max_px));
  const int polygon_cells = cv::countNonZero(raster.mask);
  const double f = shot.focal_px();
  for (size_t s = 0; s < segments.size(); ++s) {
    SegmentFit fit;
    fit.segment = int(s);
    fit.n = segments[s].indices.size();
    fits.push_back(fit);
    SegmentFit& out = fits.back();
    if (out.n == 0 || polygon_cells == 0 || !back_project_onto_plane(shot, polygon, segments[s].plane)) continue;
    cv::Mat splats = cv::Mat::zeros(raster.mask.size(), CV_8U);
    for (const int i : segments[s].indices) {
      if (!cloud.visible_in(size_t(i), shot_index)) continue;
      const Eigen::Vector3d& X = cloud.positions[size_t(i)];
      const auto uv = shot.project(X);
      if (!uv || !point_in_polygon(polygon, *uv)) continue;
      ++out.m;
      const double z = shot.to_camera(X).z();
      // At least one cell; at most the raster (a point near the camera covers everything anyway).
      const double radius_cells = std::clamp(f * segments[s].mean_spacing / z * raster.scale, 0.5,
                                             double(std::max(raster.mask.cols, raster.mask.rows)));
      const Eigen::Vector2d c = (*uv - raster.origin) * raster.scale;
      cv::circle(splats, cv::Point(int(std::lround(c.x() * 16)), int(std::lround(c.y() * 16))),
                 int(std::lround(radius_cells * 16)), cv::Scalar(255), cv::FILLED, cv::LINE_8, 4);
    }
    if (out.m == 0) continue;
    cv::Mat covered;
    cv::bitwise_and(splats, raster.mask, covered);
    out.r = double(cv::countNonZero(covered)) / double(polygon_cells);
    out.h = double(out.m) * out.r / double(out.n);
  }
  return fits;
}

CandidateChoice choose_candidate(const std::vector<SegmentFit>& fits, const CloudFitOptions& options) {
  CandidateChoice c;
  for (const SegmentFit& f : fits)
    if (f.h >= options.acceptance_h && (!c.best || f.h > c.best->h)) c.best = f;
  if (!c.best) return c;
  for (const SegmentFit& f : fits)
    if (f.segment != c.best->segment && f.h >= options.acceptance_h && c.best->h - f.h <= options.equal_margin_h)
      c.ambiguous = true;
  return c;
}

std::optional<std::vector<Eigen::Vector3d>> back_project_onto_plane(const Shot& shot, const Polygon2d& polygon,
                                                                    const Eigen::Vector4d& plane) {
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d n = plane.head<3>();
  for (const Eigen::Vector2d& uv : polygon) {
    const Eigen::Vector3d d = shot.ray_world(uv);
    const double nd = n.dot(d);
    if (!(std::fabs(nd) >= 1e-9)) return std::nullopt;
    const double t = -(n.dot(shot.C_world) + plane[3]) / nd;
    if (!(t > 0) || !std::isfinite(t)) return std::nullopt;
    out.push_back(shot.C_world + t * d);
  }
  return out;
}

std::optional<Eigen::Vector4d> fit_plane(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) return std::nullopt;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& p : points) mean += p;
  mean /= double(points.size());
  Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
  for (const auto& p : points) scatter += (p - mean) * (p - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(scatter);
  if (eig.info() != Eigen::Success) return std::nullopt;
  const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
  if (!(lambda[2] > 0) || !(lambda[1] > 1e-12 * lambda[2])) return std::nullopt;
  const Eigen::Vector3d n = eig.eigenvectors().col(0).normalized();
  const Eigen::Vector4d plane(n.x(), n.y(), n.z(), -n.dot(mean));
  if (!plane.allFinite()) return std::nullopt;
  return plane;
}

double plane_angle_deg(const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
  const Eigen::Vector3d na = a.head<3>().normalized(), nb = b.head<3>().normalized();
  return std::atan2(na.cross(nb).norm(), std::fabs(na.dot(nb))) * 180.0 / M_PI;
}

}  // namespace hf::photogrammetry
