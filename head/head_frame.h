// The head frame Kubásková's method assumes (x across the face, y towards the nose tip, z up), found on a mesh in
// any pose and unit, and the similarity that maps the input into it. Every output of head/ is reported in the
// input's frame; the head frame only decides directions ("extreme x", "above", "towards the nose").
//
// Stages (one function each in head_frame.cpp):
//   1. centroid and principal axes of the surface (area-weighted triangle centroids);
//   2. the mirror-symmetry plane: from each principal axis as a start, an iterated reflect / nearest-neighbour /
//      re-fit of the plane (the pairs p, q = NN(reflect(p)) give the normal as the principal direction of p - q
//      and the offset as the mean of the midpoints), trimmed to the best 80 % of pairs; the start with the least
//      residual wins. x is the plane's normal;
//   3. the nose tip: among vertices within `band` of the plane, the one where the surface falls away from its
//      tangent plane most in its least-falling direction, summed over the scales rho and rho / 2 with
//      rho = cap_scale x the surface's RMS radius
//      (a cap-likeness: the nose tip is a cap, a neck stump's cut, a bust's base and a crown's rim are ridges,
//      the back of the head is a cap of much larger radius, an open border is excluded). y is the tip's normal
//      (mean over rho / 2) projected into the plane;
//   4. z = x cross y, its sign from two cues, the more decisive (larger |log ratio|) winning: the profile 1 .. 3
//      rho from the tip lies farther behind it above (nasion, forehead) than below (lips, chin); the head is
//      wider 1 .. 2.5 rho above the tip (temples, eyes) than below (jaw). x = y cross z;
//   5. scale: 1 / (mean edge length), so head-frame lengths count edges, the resolution the k-neighbourhoods and
//      tolerances live at.
// Failure modes: hf::Error when the mesh has fewer than 50 vertices in triangles or no vertex near the plane can be scored.
// The nose tip, the symmetry residual and the cap score are reported so a caller can judge the result.
#pragma once

#include <Eigen/Core>
#include <string>

#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

struct HeadFrame {
  // p_head = scale * R_head_input * (p_input - origin_input); origin_input is the nose tip.
  Eigen::Matrix3d R_head_input = Eigen::Matrix3d::Identity();
  Eigen::Vector3d origin_input = Eigen::Vector3d::Zero();
  double scale = 1.0;
  int nose_tip_vertex = -1;
  double mean_edge_length = 0.0;     // input units
  double symmetry_rms_edges = 0.0;   // trimmed RMS mirror residual, in mean edge lengths
  double cap_score_edges = 0.0;      // the tip's cap score (both scales, head_frame.cpp) x the mean edge length
  double cap_scale = 0.0;            // rho, input units
  double recession_above = 0.0, recession_below = 0.0;  // stage 4's mean recession, in mean edge lengths
  double width_above = 0.0, width_below = 0.0;          // stage 4's head widths, in mean edge lengths
  Eigen::Vector3d to_head(const Eigen::Vector3f& p) const {
    return scale * (R_head_input * (p.cast<double>() - origin_input));
  }
};

struct HeadFrameOptions {
  int symmetry_samples = 1500;    // vertices (every n-th) the mirror fit uses
  int symmetry_iterations = 15;
  double band_edges = 1.5;        // half-width of the band of nose-tip candidates, in mean edge lengths
  double cap_scale = 0.17;        // rho / RMS radius of the surface: 2.1 cm on libigl's head and neck (12.3 cm)
};

HeadFrame find_head_frame(const TriangleMesh& mesh, const MeshTopology& topology, const HeadFrameOptions& options = {});

}  // namespace hf::head
