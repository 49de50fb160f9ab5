// Visual guidance (Kellner section 5.3): the state a sketched polygon is in, and the placement it implies.
//
//   red     no plane to project the outline onto: no existing polygon chosen (section 4.3), no cloud segment whose
//           fit h passes the acceptance threshold (section 4.2), and fewer than two shots whose rays fix every vertex
//           (section 4.1). Nothing is placed ("not a guess").
//   yellow  a 3D polygon can be suggested but may be inaccurate or ambiguous: two or more accepted cloud segments of
//           equal quality, or multi-shot sketching with exactly two shots.
//   green   an accurate polygon with no interfering candidate: the plane of a chosen polygon, three or more shots, or
//           a single accepted cloud segment.
// When several apply the most accurate wins, in this order: polygon plane, >= 3 shots, unique cloud segment, two
// shots, ambiguous cloud segments.
#pragma once

#include <string>

namespace hf::photogrammetry {

enum class Guidance { red, yellow, green };
enum class Placement { none, dlt, cloud_plane, polygon_plane };
const char* to_string(Guidance g);
const char* to_string(Placement m);  // "none", "dlt", "cloud_plane", "polygon_plane" (polygons.json's "method")

struct GuidanceInputs {
  bool reference_plane = false;   // same_plane_as names a polygon that has a plane
  int shots = 0;                  // views the polygon is sketched in
  bool dlt_ok = false;            // every vertex triangulated (needs shots >= 2)
  bool cloud_candidate = false;   // an accepted cloud segment
  bool cloud_ambiguous = false;   // ... with a rival of equal quality
};

struct GuidanceDecision {
  Guidance state = Guidance::red;
  Placement method = Placement::none;
  std::string reason;  // one sentence for reports
};

GuidanceDecision decide_guidance(const GuidanceInputs& in);

}  // namespace hf::photogrammetry
