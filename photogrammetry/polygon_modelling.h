// From a sketch to 3D polygons (Kellner sections 4-5): for each sketched polygon, in the sketch's order,
//   1. the cloud's planar segments are fitted to the outline of its first view (single-shot sketching, 4.2);
//   2. every vertex sketched in two or more views is triangulated (DLT, 4.1);
//   3. the guidance rules (photogrammetry/guidance.h) decide the state and the placement:
//      polygon_plane  the first view's outline back-projected onto the plane of the polygon named by same_plane_as;
//      dlt            the triangulated vertices, projected orthogonally onto their least-squares plane; when an
//                     accepted cloud segment's plane lies within adjust_to_segment_deg of that plane, onto the
//                     segment's plane instead (section 4.2's last sentence);
//      cloud_plane    the first view's outline back-projected onto the best segment's plane;
//      none (red)     no vertices, no plane.
//   4. each placed vertex's reprojection error: the RMS over the polygon's views of |sketched - projected| (pixels).
// Frames and units are the network's. Nothing here throws for any sketch check_sketch_shots() accepts; every number
// reported is finite.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "photogrammetry/dlt_triangulation.h"
#include "photogrammetry/guidance.h"
#include "photogrammetry/network.h"
#include "photogrammetry/ransac_planes.h"
#include "photogrammetry/single_shot_sketching.h"
#include "photogrammetry/sketch.h"

namespace hf::photogrammetry {

struct ModelOptions {
  RansacPlaneOptions ransac;
  CloudFitOptions fit;
  DltOptions dlt;
  double adjust_to_segment_deg = 10.0;  // section 4.2; 0: never adjust
};

struct ModelledPolygon {
  std::string id;
  GuidanceDecision decision;
  std::vector<Eigen::Vector3d> vertices;        // empty when red
  std::optional<Eigen::Vector4d> plane;         // (n, d), n . X + d = 0, |n| = 1; n faces the first view's camera
  std::vector<double> reprojection_error_px;    // per vertex
  std::vector<SegmentFit> fits;                 // the first view's fit to every segment
  std::optional<SegmentFit> candidate;          // the accepted best segment, if any
  bool adjusted_to_segment = false;
  std::vector<Triangulation> triangulations;    // per vertex, when sketched in >= 2 views
};

struct Model {
  std::vector<PlaneSegment> segments;
  std::vector<ModelledPolygon> polygons;  // the sketch's order
};

// Segments the cloud (options.ransac) and models every polygon of the sketch.
Model model_polygons(const Network& network, const Sketch& sketch, const ModelOptions& options = {});
// The same with segments computed beforehand (benchmarks, interactive use).
Model model_polygons(const Network& network, const Sketch& sketch, std::vector<PlaneSegment> segments,
                     const ModelOptions& options = {});

}  // namespace hf::photogrammetry
