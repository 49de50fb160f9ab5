// Cell-by-cell validation against a ground-truth raster (Cvirn section 5.1): per class, true positives are
// cells of the class in both rasters, false positives cells only the result puts in it, false negatives cells
// only the truth does; completeness = TP / (TP + FN) (eq. 7), correctness = TP / (TP + FP) (eq. 8), F1 their
// harmonic mean (eq. 9). A class absent from both rasters is "not contained" (contained = false; its scores are
// 0 and must not be averaged); a ratio with a zero denominator is 0, never NaN.
#pragma once

#include <array>
#include <cstdint>

#include "lidar/connected_components.h"
#include "lidar/differential_profile.h"

namespace hf::lidar {

struct Scores {
  std::int64_t tp = 0, fp = 0, fn = 0;
  bool contained = false;  // the class occurs in the result or in the truth
  double completeness = 0, correctness = 0, f1 = 0;
};

// Scores from counts (eqs. 7-9).
Scores scores_from_counts(std::int64_t tp, std::int64_t fp, std::int64_t fn);

// Binary masks (e.g. the building raster S against rasterised cadastral footprints), counting only the cells
// where `where` is set (all cells when null).
Scores compare_masks(const Mask& result, const Mask& truth, const Mask* where = nullptr);

struct ClassValidation {
  std::array<Scores, kBuiltUpClasses> per_class;  // index = class - 1
  double mean_f1 = 0;  // over the contained classes: the single number per dataset of the paper's Table 2
};

// Class rasters of BuiltUpClass values (same size).
ClassValidation compare_classes(const Image<std::uint8_t>& result, const Image<std::uint8_t>& truth);

}  // namespace hf::lidar
