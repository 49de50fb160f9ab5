// Important areas of a head (Kubásková section 3.3): eyes, nose, lips and ears, found from the discrete mean
// curvature and then separated.
//   1. F = {valid v : H(v) >= mean H} (the threshold is the average evaluation);
//   2. close^k, open^k, close^k, then (optionally) dilate^k, with k = 5 for N <= 13000 vertices, 10 up to 20000,
//      15 above (the paper's experimental choice; `k` overrides it);
//   3. the face area, bounded by a box in the head frame (sizes in rho, head_frame.h), and the ears: per side the
//      largest thin-sheet piece (a flap: surface facing the other way right behind it, the pinna) beside and behind
//      the face, when it spans at least 1 rho and its centre lies where an ear can (ear_implausible below; else the
//      next largest that does); a side without one (hair, not scanned, only a fin fused behind the head) has no ear
//      area and `note` says why (important_areas.cpp has the why of both);
//   4. the face area is split in the head frame (head_frame.h; x towards the subject's right, y towards the
//      nose, z up, origin at the nose tip). Method 1 (distance): eyes/nose boundary at half the height of the
//      face area's widest point (max |x|), nose/lips boundary two thirds of the way from the tip down to the
//      face area's lowest point. Method 2: as method 1, but the nose is every mesh vertex in the box between the
//      nose/lips boundary and the eyes/nose boundary, in front of the nose root (the deepest point of the profile
//      above the tip), as wide as the face area is in that band near the tip (the area of fig. 5). The eyes
//      leave out the bridge between them (|x| under half the nose's half-width). When the morphology left an eye
//      side (nearly) empty (a decimated mesh), both eyes are the face's band above the eyes/nose boundary instead
//      (`note` says so).
// Labels are per vertex; every vertex has exactly one (none where no area).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "head/curvature.h"
#include "head/head_frame.h"
#include "head/thresholding.h"
#include "mesh/topology.h"

namespace hf::head {

enum class Area : std::uint8_t { none = 0, eye_right, eye_left, nose, lips, ear_right, ear_left };
constexpr int kAreaCount = 7;
const char* area_name(Area a);

struct ImportantAreaOptions {
  int k = 0;              // 0: the paper's choice by vertex count (5 / 10 / 15), unless k_rho says otherwise
  // > 0 (and k = 0): k at a physical scale, round(k_rho x rho / mean edge length) (head_frame.h's rho and edge),
  // so the morphology spans the same extent on meshes of one head at different vertex densities.
  double k_rho = 0.0;
  // > 0: the eyes/nose boundary at root_fraction x the nose root's height above the tip instead of step 4's half
  // the height of the face area's widest feature. The widest feature is one vertex, an extreme of a set that on a
  // noisy (fused) mesh reaches the face box's sides at any height; the root is a minimum of the profile, averaged.
  double root_fraction = 0.0;
  bool final_dilation = true;
  int separation_method = 2;  // 1 or 2 (section 3.3)
};

struct ImportantAreas {
  std::vector<Area> label;  // per vertex
  VertexMask features;      // step 1's thresholded set, before morphology
  VertexMask area_mask;     // after step 2
  int k = 0;
  double threshold = 0;     // mean H used in step 1 (1 / mesh unit)
  // Boundaries in head-frame z (mean edge lengths below/above the tip).
  double z_eyes_nose = 0, z_nose_lips = 0;
  // The nose root (nasion): the profile's deepest point 0 .. 2.5 rho above the tip (z: the mean over the profile
  // vertices within 0.05 rho of the deepest y), and method 2's nose half-width; head units.
  double z_root = 0, y_root = 0, nose_half_width = 0;
  std::array<int, kAreaCount> counts{};
  // Per area, why it is absent or how it was found when not by the steps above (empty otherwise): an ear side
  // without an ear-like flap (hair, not scanned), the eyes' fallback band on a mesh whose morphology removed them.
  std::array<std::string, kAreaCount> note{};
  std::array<double, 2> ear_flap_span_rho{};  // right, left: the ear's flap span, or the largest piece's (0: none)
  // Right, left: the ear's flap centroid, head frame in rho (zero when the side has no ear).
  std::array<Eigen::Vector3d, 2> ear_centre_rho{Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
};

// Whether a flap centred at `centre_rho` (head frame, in rho) can be an ear: "" if so, else why not. An ear's centre
// lies beside the head at about the nose's height and in front of the back of the head: at most 7.5 rho behind the
// nose tip and 0.5 rho above it (head_frame.h's y follows the tip's normal, which tilts up on the source heads, so
// ears sit 0.9 .. 3.4 rho below the tip in this frame). Chosen on the four source heads, whose found ears lie at y
// -6.7 .. -3.6 and z -3.4 .. -0.9 rho; the fins a TSDF fuses behind and above a head's silhouette (y -8 .. -9.3,
// z up to +1.9) and Nefertiti's crown (y -10.5, z +0.9) fail it (bench/results/head.md). The sides (|x| >= 2 rho,
// beyond the outer eye corners at 1.5 .. 2.5 rho) and y < -1.5 rho are step 3's search region already.
std::string ear_implausible(const Eigen::Vector3d& centre_rho);

int paper_k_for_vertex_count(int n);

ImportantAreas find_important_areas(const TriangleMesh& mesh, const MeshTopology& topology,
                                    const VertexCurvatures& discrete, const HeadFrame& frame,
                                    const ImportantAreaOptions& options = {});

}  // namespace hf::head
