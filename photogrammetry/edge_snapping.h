// Sketching with snapping in the shot view (Kellner section 5.2): line segments detected in the shot by the Line
// Segment Detector of von Gioi et al. (OpenCV's cv::createLineSegmentDetector, restored in OpenCV 4.5.1), and each
// sketched edge snapped to the image lines that match it -- nearly parallel (within max_angle_deg) and spatially
// close (both end points within max_distance_px of the edge's line, and overlapping the edge along it). The matched
// lines of an edge are merged into one line (length-weighted total least squares through their end points);
// consecutive snapped lines are intersected and the intersections are the snapped polygon's vertices. An edge with
// no match keeps the sketched edge ("the initial edge will be used"); a vertex whose two lines are parallel, or whose
// intersection lands farther than max_vertex_move_px from the sketch, keeps the sketched vertex; a snapped outline
// that intersects itself is discarded for the sketch.
//
// Pixels as everywhere (OpenCV's convention). Thread-safety: reentrant (a detector per call).
#pragma once

#include <vector>

#include "core/image.h"
#include "photogrammetry/polygon2d.h"

namespace hf::photogrammetry {

struct LineSegment2 {
  Eigen::Vector2d a, b;  // end points, pixels
};

// LSD with its standard refinement on the image's luma.
std::vector<LineSegment2> detect_line_segments(const ColorImage& image);

struct SnapOptions {
  double max_angle_deg = 10.0;  // a rough 2-3 px sketch of a 30 px window edge tilts it by up to ~10 degrees
  double max_distance_px = 6.0;
  double min_segment_px = 8.0;       // shorter detections are ignored (texture, noise)
  double max_vertex_move_px = 15.0;  // 2.5 x max_distance: a snapped corner cannot wander off
};

struct EdgeSnap {
  std::vector<int> lines;  // indices of the matched segments; empty: the sketched edge kept
  Eigen::Vector2d p0, p1;  // the edge's line after snapping (two points on it)
};

struct SnapResult {
  Polygon2d points;            // the snapped outline (the sketch when nothing snapped)
  std::vector<EdgeSnap> edges;  // edge k runs from vertex k to vertex k + 1
  bool snapped = false;        // at least one edge matched and the result was kept
};

SnapResult snap_polygon(const Polygon2d& sketch, const std::vector<LineSegment2>& lines,
                        const SnapOptions& options = {});

}  // namespace hf::photogrammetry
