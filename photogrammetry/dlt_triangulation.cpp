#include "photogrammetry/dlt_triangulation.h"

#include <Eigen/Geometry>
#include <Eigen/SVD>
#include <cmath>
#include <limits>

namespace hf::photogrammetry {

const char* to_string(TriangulationStatus s) {
  switch (s) {
    case TriangulationStatus::ok: return "ok";
    case TriangulationStatus::too_few_views: return "too_few_views";
    case TriangulationStatus::degenerate: return "degenerate";
    case TriangulationStatus::behind_camera: return "behind_camera";
  }
  return "unknown";
}

DltObservation observation(const Shot& shot, const Eigen::Vector2d& pixel) {
  return {shot.P(), shot.C_world, pixel};
}

double reprojection_error_px(const Matrix34d& P, const Eigen::Vector3d& X, const Eigen::Vector2d& x) {
  const Eigen::Vector3d p = P * X.homogeneous();
  if (!(p.z() > 0)) return std::numeric_limits<double>::infinity();
  return (p.head<2>() / p.z() - x).norm();
}

Triangulation triangulate_dlt(const std::vector<DltObservation>& views, const DltOptions& options) {
  Triangulation out;
  if (views.size() < 2) return out;
  // Conditioning: X = origin + scale * X_n, so P [X; 1] = P T [X_n; 1] with T = [scale I, origin; 0, 1].
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();
  for (const DltObservation& v : views) origin += v.C_world;
  origin /= double(views.size());
  double spread = 0;
  for (const DltObservation& v : views) spread += (v.C_world - origin).squaredNorm();
  double scale = std::sqrt(spread / double(views.size()));
  if (!(scale > 0) || !std::isfinite(scale)) scale = 1.0;
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.topLeftCorner<3, 3>() *= scale;
  T.topRightCorner<3, 1>() = origin;

  Eigen::MatrixXd A(2 * views.size(), 4);
  for (size_t k = 0; k < views.size(); ++k) {
    const Eigen::Matrix<double, 3, 4> P = views[k].P * T;
    A.row(Eigen::Index(2 * k)) = views[k].x.x() * P.row(2) - P.row(0);
    A.row(Eigen::Index(2 * k + 1)) = views[k].x.y() * P.row(2) - P.row(1);
  }
  for (Eigen::Index r = 0; r < A.rows(); ++r) {
    const double n = A.row(r).norm();
    if (n > 0) A.row(r) /= n;
  }
  if (!A.allFinite()) {
    out.status = TriangulationStatus::degenerate;
    return out;
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(A, Eigen::ComputeFullV);
  const Eigen::Vector4d Xh = svd.matrixV().col(3);
  // A point at infinity (parallel rays) or a 2-D null space (coincident rays: the smallest two singular values
  // both vanish) fixes no point.
  const Eigen::Vector4d s = [&] {
    Eigen::Vector4d v = Eigen::Vector4d::Zero();
    v.head(svd.singularValues().size()) = svd.singularValues();
    return v;
  }();
  if (!(std::fabs(Xh.w()) > 1e-12 * Xh.norm()) || !(s[2] > 1e-12 * s[0])) {
    out.status = TriangulationStatus::degenerate;
    return out;
  }
  const Eigen::Vector3d X = origin + scale * (Xh.head<3>() / Xh.w());
  if (!X.allFinite()) {
    out.status = TriangulationStatus::degenerate;
    return out;
  }
  double max_angle = 0;
  for (size_t a = 0; a < views.size(); ++a)
    for (size_t b = a + 1; b < views.size(); ++b) {
      const Eigen::Vector3d ra = X - views[a].C_world, rb = X - views[b].C_world;
      const double c = ra.cross(rb).norm(), d = ra.dot(rb);
      max_angle = std::max(max_angle, std::atan2(c, d) * 180.0 / M_PI);
    }
  out.max_angle_deg = max_angle;
  if (!(max_angle >= options.min_angle_deg)) {
    out.status = TriangulationStatus::degenerate;
    return out;
  }
  std::vector<double> errors;
  for (const DltObservation& v : views) {
    const double e = reprojection_error_px(v.P, X, v.x);
    if (!std::isfinite(e)) {
      out.status = TriangulationStatus::behind_camera;
      return out;
    }
    errors.push_back(e);
  }
  out.status = TriangulationStatus::ok;
  out.X_world = X;
  out.reprojection_error_px = std::move(errors);
  return out;
}

}  // namespace hf::photogrammetry
