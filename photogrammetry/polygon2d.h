// Planar polygon helpers in pixel coordinates (or any 2D frame): the tests the sketches need.
// A polygon is its vertex list in order, closed implicitly (last to first); no vertex is repeated at the end.
#pragma once

#include <Eigen/Core>
#include <vector>

namespace hf::photogrammetry {

using Polygon2d = std::vector<Eigen::Vector2d>;

// Signed area (shoelace): positive when the vertices run counter-clockwise in a y-up frame (clockwise on screen).
double signed_area(const Polygon2d& polygon);
// Even-odd rule; a point on an edge may count either way.
bool point_in_polygon(const Polygon2d& polygon, const Eigen::Vector2d& p);
// Whether two non-adjacent edges touch or cross, or two adjacent edges fold back onto each other (a zero-length
// edge counts as self-intersecting). O(n^2), for sketches of a few dozen vertices.
bool self_intersecting(const Polygon2d& polygon);
// The intersection of the infinite lines through (a0, a1) and (b0, b1); false when they are parallel within
// sin(angle) < 1e-9.
bool intersect_lines(const Eigen::Vector2d& a0, const Eigen::Vector2d& a1, const Eigen::Vector2d& b0,
                     const Eigen::Vector2d& b1, Eigen::Vector2d* out);

}  // namespace hf::photogrammetry
