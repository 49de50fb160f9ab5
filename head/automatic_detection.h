// Area-specific features, Kubásková's automatic detection (section 4.5): each important area is thresholded with
// the evaluation that worked best there on the paper's models, at that evaluation's average over the area
// (after eq. 10's normalisation):
//   eyes  MLS k_max          ears  MLS mean curvature
//   lips  discrete mean curvature with the top 5 % truncated (section 3.1.3's truncation)
//   nose  discrete k_max
// A vertex outside every area is never a feature.
#pragma once

#include "head/curvature.h"
#include "head/important_areas.h"
#include "head/thresholding.h"

namespace hf::head {

struct AreaFeatures {
  VertexMask features;                 // union over the areas
  std::array<double, kAreaCount> threshold_percent{};  // the per-area threshold used (eq. 10 %)
};

// `mls` must be valid on the eye and ear areas (mls_curvature(..., only = those areas) is enough).
// mls_truncate_percent > 0 truncates the eyes' and ears' MLS evaluations' top percentage first, as the lips' (the
// paper does not; head_features.h's physical scales do: on a fused head a few spikes in an eye area lift its average
// above all but a handful of vertices, bench/results/head.md).
AreaFeatures detect_area_features(const ImportantAreas& areas, const VertexCurvatures& discrete,
                                  const VertexCurvatures& mls, double mls_truncate_percent = 0.0);

}  // namespace hf::head
