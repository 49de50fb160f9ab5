// Point-cloud-supported single-shot sketching (Kellner section 4.2) and the plane of an existing polygon (4.3).
//
// A polygon sketched in one shot is compared with every planar segment of the cloud (photogrammetry/ransac_planes.h):
// the segment's points visible from the shot are projected into it, m of its n points fall inside the polygon, and
// the uniformity r in [0, 1] is the fill ratio of the polygon's raster when every inside point is splatted as a disc
// of radius q (the segment's mean nearest-neighbour distance, eq. 2) projected to pixels at the point's depth,
// f q / z. The fit is h = m r / n (eq. 1). A segment whose plane the polygon's rays do not all hit in front of the
// shot gets h = 0. The raster is the polygon's bounding box scaled to at most raster_max_px on its longer side (the
// fill ratio is a fraction, so the scale changes it only at splat-size granularity; a splat covers at least one
// raster cell).
//
// Visibility: a point with a visibility list is projected only into the shots that saw it (Cloud::visible_in).
// Acceptance (section 4.2, "adjustable"): the best h at or above acceptance_h is the candidate; a second segment
// within equal_margin_h of it makes the choice ambiguous (section 5.3's "two or more candidates of equal quality").
#pragma once

#include <optional>
#include <vector>

#include "photogrammetry/network.h"
#include "photogrammetry/polygon2d.h"
#include "photogrammetry/ransac_planes.h"

namespace hf::photogrammetry {

struct CloudFitOptions {
  double acceptance_h = 0.3;   // h of a facade sketched whole on a cloud with holes of ~half its area
  double equal_margin_h = 0.05;
  int raster_max_px = 256;
};

struct SegmentFit {
  int segment = -1;       // index into the segments given
  size_t m = 0, n = 0;    // points inside the polygon, points of the segment
  double r = 0.0;         // fill ratio
  double h = 0.0;         // m r / n
};

// One fit per segment, in the segments' order.
std::vector<SegmentFit> fit_segments(const Shot& shot, int shot_index, const Polygon2d& polygon, const Cloud& cloud,
                                     const std::vector<PlaneSegment>& segments, const CloudFitOptions& options = {});

struct CandidateChoice {
  std::optional<SegmentFit> best;  // the best fit at or above acceptance_h
  bool ambiguous = false;          // another accepted fit within equal_margin_h of the best
};
CandidateChoice choose_candidate(const std::vector<SegmentFit>& fits, const CloudFitOptions& options = {});

// Each pixel's ray from the shot intersected with plane (n, d); nullopt when a ray is parallel to the plane (|n . ray|
// < 1e-9) or meets it behind the camera.
std::optional<std::vector<Eigen::Vector3d>> back_project_onto_plane(const Shot& shot, const Polygon2d& polygon,
                                                                    const Eigen::Vector4d& plane);

// The least-squares plane (n, d) through points (the smallest principal axis of their scatter); nullopt for fewer
// than three points or collinear ones (the two smallest scatter eigenvalues within 1e-12 of the largest).
std::optional<Eigen::Vector4d> fit_plane(const std::vector<Eigen::Vector3d>& points);

// The angle between two planes' normals in degrees, in [0, 90] (orientation ignored).
double plane_angle_deg(const Eigen::Vector4d& a, const Eigen::Vector4d& b);

}  // namespace hf::photogrammetry
