// SKETCH.json: the 2D polygons a user sketched on the shots (the input of `hashfusion model`). Stable format:
//
//   {"polygons": [{"id": "p1",
//                  "views": [{"shot": "templeR0013.png", "points": [[u, v], ...]}, ...],
//                  "same_plane_as": "p0"}]}
//
// A shot is named by its image file name (Shot::name); pixel coordinates as OpenCV's (u right, v down, the top-left
// pixel's centre at (0, 0)). Vertex k of one view and vertex k of another are the same 3D corner, so every view of a
// polygon has the same number of vertices (3..kMaxSketchVertices). "same_plane_as" (optional) names a polygon listed
// before this one: the new polygon is placed on that polygon's plane (section 4.3).
//
// parse_sketch checks the structure: unique non-empty ids, at least one view, a shot at most once per polygon,
// equal vertex counts, no self-intersecting outline, same_plane_as naming an earlier polygon. check_sketch_shots
// checks it against a network: every shot exists and every vertex lies inside its image.
// Failure modes: hf::ParseError "FILE: polygon 'p1' view 2: expected ..." (ids and names quoted, printable).
#pragma once

#include <string>
#include <vector>

#include "photogrammetry/network.h"
#include "photogrammetry/polygon2d.h"

namespace hf::photogrammetry {

inline constexpr size_t kMaxSketchVertices = 1000;
inline constexpr size_t kMaxSketchPolygons = 100000;
inline constexpr double kMaxSketchPixel = 1e6;  // |u|, |v| beyond it lie outside any image: refused as read

struct SketchView {
  std::string shot;
  Polygon2d points;  // pixels
};

struct SketchPolygon {
  std::string id;
  std::vector<SketchView> views;
  std::string same_plane_as;  // empty: none
};

struct Sketch {
  std::vector<SketchPolygon> polygons;
};

Sketch parse_sketch(const std::string& text, const std::string& name_for_errors);
Sketch read_sketch(const std::string& path);
void check_sketch_shots(const Sketch& sketch, const Network& network, const std::string& name_for_errors);

}  // namespace hf::photogrammetry
