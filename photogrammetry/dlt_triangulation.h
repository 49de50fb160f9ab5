// Multi-shot sketching (Kellner section 4.1): a polygon vertex sketched in two or more shots is placed at the
// intersection of its rays by the homogeneous linear triangulation (DLT) of Hartley and Zisserman, "Multiple View
// Geometry", 2nd ed., section 12.2: each view adds the rows u p3^T - p1^T and v p3^T - p2^T of A, and X is the right
// singular vector of A's smallest singular value (the least-squares solution of A X = 0, |X| = 1).
//
// Conditioning (HZ 4.4.4): the world is translated to the centroid of the camera centres and scaled by their RMS
// distance from it (unit scale for a single centre), and each row of A is scaled to unit length, so the solution
// does not depend on the units of the network or on the pixel scale.
//
// Outcomes (never NaN or inf): ok; too_few_views (< 2); degenerate: the rays do not fix a point -- parallel rays
// (the solution lies at infinity, |w| <= 1e-12 |X_h|), coincident rays, or every pair of rays within
// min_angle_deg of each other at the solution; behind_camera: the intersection lies behind a shot. Only ok carries
// a point; the errors are then |x_k - project_k(X)| in pixels per view, in the order given.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "photogrammetry/network.h"

namespace hf::photogrammetry {

enum class TriangulationStatus { ok, too_few_views, degenerate, behind_camera };
const char* to_string(TriangulationStatus status);

struct DltObservation {
  Matrix34d P;               // pixel ~ P [X; 1]
  Eigen::Vector3d C_world;   // the camera centre (P's null vector), for the conditioning and the angle test
  Eigen::Vector2d x;         // the observed pixel
};
DltObservation observation(const Shot& shot, const Eigen::Vector2d& pixel);

struct DltOptions {
  // Below this largest angle between two rays at the solution the point is not fixed (degenerate). 0.1 degrees:
  // a 1 px error then moves a point 10 m away by metres along the ray at 500 px focal length.
  double min_angle_deg = 0.1;
};

struct Triangulation {
  TriangulationStatus status = TriangulationStatus::too_few_views;
  Eigen::Vector3d X_world = Eigen::Vector3d::Zero();  // zero unless ok
  std::vector<double> reprojection_error_px;          // per view when ok, else empty
  double max_angle_deg = 0.0;                         // the widest pair of rays at X (0 unless ok or degenerate)
  bool ok() const { return status == TriangulationStatus::ok; }
};

Triangulation triangulate_dlt(const std::vector<DltObservation>& views, const DltOptions& options = {});

// |x - project(X)| in pixels; +inf when X is behind the camera (never NaN for finite input).
double reprojection_error_px(const Matrix34d& P, const Eigen::Vector3d& X_world, const Eigen::Vector2d& x);

}  // namespace hf::photogrammetry
