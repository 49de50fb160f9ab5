#include "photogrammetry/guidance.h"

namespace hf::photogrammetry {

const char* to_string(Guidance g) {
  switch (g) {
    case Guidance::red: return "red";
    case Guidance::yellow: return "yellow";
    case Guidance::green: return "green";
  }
  return "red";
}

const char* to_string(Placement m) {
  switch (m) {
    case Placement::none: return "none";
    case Placement::dlt: return "dlt";
    case Placement::cloud_plane: return "cloud_plane";
    case Placement::polygon_plane: return "polygon_plane";
  }
  return "none";
}

GuidanceDecision decide_guidance(const GuidanceInputs& in) {
  if (in.reference_plane) return {Guidance::green, Placement::polygon_plane, "on the plane of the chosen polygon"};
  if (in.dlt_ok && in.shots >= 3)
    return {Guidance::green, Placement::dlt, "triangulated from " + std::to_string(in.shots) + " shots"};
  if (in.cloud_candidate && !in.cloud_ambiguous)
    return {Guidance::green, Placement::cloud_plane, "one cloud segment fits the outline"};
  if (in.dlt_ok && in.shots == 2)
    return {Guidance::yellow, Placement::dlt, "triangulated from two shots only (sketch it in a third)"};
  if (in.cloud_candidate)
    return {Guidance::yellow, Placement::cloud_plane, "two or more cloud segments fit equally well"};
  std::string why = "no plane: no polygon chosen, no cloud segment passes the threshold";
  why += in.shots >= 2 ? ", and the shots' rays do not fix every vertex" : ", and fewer than two shots";
  return {Guidance::red, Placement::none, why};
}

}  // namespace hf::photogrammetry
