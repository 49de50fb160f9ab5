// What `hashfusion head-features` writes into its output folder, every file through a temporary and a rename
// (core/atomic_file.h), all positions in the input mesh's frame and units:
//   evaluations.ply       binary PLY: x y z, float mean_curvature gaussian_curvature k1 k2 (of the chosen
//                         method; discrete unless --method mls) laplace, uchar area (Area, important_areas.h),
//                         uchar feature, and the faces
//   <evaluation>.ply      one colour-mapped mesh per evaluation (mean_curvature, gaussian_curvature, k1, k2,
//                         laplace): blue (negative) - white - red (positive), saturating at the 95th percentile
//                         of |w| over valid vertices; invalid vertices grey
//   features.ply          areas coloured, feature vertices red
//   control_points.json   [{name, vertex, position}], the names not found, and absent_areas: {area: why} for an
//                         area the detection reports absent (an ear under hair: important_areas.h)
//   report.json, report.md  mesh, frame, areas, thresholds, control points, warnings, stage timings
//   features.png          front, right and left views: areas, features and control points
//   evaluation.png        front and side views of the manual evaluation, colour-mapped
// Thread-safety: none needed (no shared state). Failure: hf::Error naming the file.
#pragma once

#include <string>

#include "head/head_features.h"

namespace hf::head {

struct OutputInfo {
  std::string input_path;  // for the reports
};

void write_head_feature_outputs(const std::string& dir, const TriangleMesh& mesh, const HeadFeatureResult& result,
                                const HeadFeatureOptions& options, const OutputInfo& info);

// Colour map used above, exposed for tests: value / scale in [-1, 1] -> blue .. white .. red.
Rgb8 diverging_color(double value, double scale);

}  // namespace hf::head
