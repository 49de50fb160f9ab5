// The whole of Kubásková's method on one mesh, stage by stage: topology -> vertex evaluations (discrete, MLS,
// Laplace-Beltrami) -> head frame -> important areas -> features (manual: the chosen evaluation normalised by
// eq. 10, thresholded to [a, b], then the morphology steps; automatic: section 4.5's per-area evaluations) ->
// control points. Each stage is timed.
//
// Bad input: hf::Error for a mesh with no triangle, no interior vertex, or fewer than 50 vertices in triangles
// (head frame). Boundary, non-manifold and isolated vertices and degenerate triangles are not errors: they are
// counted in `warnings` and their evaluations are invalid (0), so no NaN reaches an output.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "head/automatic_detection.h"
#include "head/control_points.h"
#include "head/curvature.h"
#include "head/feature_spec.h"
#include "head/head_frame.h"
#include "head/important_areas.h"
#include "head/laplace_beltrami.h"
#include "head/mls_curvature.h"
#include "head/morphology.h"
#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

struct HeadFeatureOptions {
  Evaluation evaluation = Evaluation::discrete;  // the manual features' evaluation (--method)
  Quantity quantity = Quantity::mean;            // which curvature of discrete / mls (Laplace: its magnitude)
  bool has_threshold = false;  // false: a = the evaluation's average (section 4.5's rule), b = 100
  ThresholdRange threshold;
  double truncate_percent = 0;  // section 3.1.3's truncation of the top percentage, before eq. 10
  std::vector<MorphologyStep> morphology;
  bool automatic = false;  // section 4.5: per-area evaluations replace the manual features
  MlsOptions mls;
  HeadFrameOptions frame;
  ImportantAreaOptions areas;
  // Physical scale, in rho (head_frame.h: 0.17 x the surface's RMS radius, ~2 cm on a head): > 0 smooths every
  // vertex evaluation (discrete, Laplace-Beltrami, MLS) over a Gaussian of sigma = evaluation_sigma_rho x rho
  // (curvature.h's smooth_at_scale), and mls_h_rho > 0 sets the MLS fit's h to mls_h_rho x rho (mls_curvature.h).
  // With areas.k_rho they make every scale of the method a length on the head rather than a count of vertices or
  // rings, for meshes of one head at different densities or noise (a fused head against its source). 0 (the
  // default): the paper's scales (1-ring operators, MLS over 3 rings with h the 1-ring edge), on which the
  // real-head tests were chosen. use_physical_scale() below sets the values chosen on the fused libigl head
  // (bench/results/head.md, "End to end").
  double evaluation_sigma_rho = 0.0;
  double mls_h_rho = 0.0;
  double mls_truncate_percent = 0.0;  // automatic_detection.h: the eyes' and ears' MLS evaluations truncated (0: none)
};

// Every scale of the method a length on the head, as chosen end to end on libigl's head fused at 3 mm voxels
// from two orbit rings (bench/results/head.md, "End to end": control points' median distance to the source's
// 3.9 -> 1.7 voxels): evaluations smoothed over sigma = 0.05 rho (~1 mm, a third of a voxel: the fused surface's
// 1-ring ripple), the MLS fit over h = 0.5 rho (~1 cm: the eyelid fold's width), the eyes/nose boundary at 0.3 of
// the nose root's height (0.30 on libigl's source: 12.5 of 41.1 mm), the eyes' and ears' MLS evaluations
// truncated by 5 % as the lips' are (an eye's features fell to 6 vertices on one noise seed without). The
// morphology's k stays the paper's (k_rho 0.7 .. 1.4 measured no better there).
void use_physical_scale(HeadFeatureOptions& options);

struct HeadFeatureResult {
  MeshTopology topology;
  VertexCurvatures discrete, mls;  // mls: all vertices for --method mls, else only the eye and ear areas
  LaplaceBeltrami laplace;
  std::vector<float> evaluation_percent;  // the manual evaluation after eq. 10
  float threshold_a = 0, threshold_b = 100;
  VertexMask features;  // the reported features (manual or automatic)
  HeadFrame frame;
  ImportantAreas areas;
  AreaFeatures area_features;
  std::vector<ControlPoint> control_points;
  std::vector<std::string> warnings;
  std::map<std::string, double> stage_ms;
};

HeadFeatureResult detect_head_features(const TriangleMesh& mesh, const HeadFeatureOptions& options = {});

// The manual evaluation's raw values (before eq. 10) and validity for the options' evaluation and quantity.
const std::vector<float>& raw_evaluation(const HeadFeatureResult& r, const HeadFeatureOptions& options,
                                         const VertexMask** valid);

}  // namespace hf::head
