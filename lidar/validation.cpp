#include "lidar/validation.h"

#include "core/error.h"

namespace hf::lidar {

Scores scores_from_counts(std::int64_t tp, std::int64_t fp, std::int64_t fn) {
  Scores s;
  s.tp = tp, s.fp = fp, s.fn = fn;
  s.contained = tp + fp + fn > 0;
  s.completeness = tp + fn > 0 ? double(tp) / double(tp + fn) : 0.0;
  s.correctness = tp + fp > 0 ? double(tp) / double(tp + fp) : 0.0;
  s.f1 = s.completeness + s.correctness > 0 ? 2.0 * s.completeness * s.correctness / (s.completeness + s.correctness) : 0.0;
  return s;
}

Scores compare_masks(const Mask& result, const Mask& truth, const Mask* where) {
  if (result.width() != truth.width() || result.height() != truth.height() ||
      (where && (where->width() != truth.width() || where->height() != truth.height())))
    throw Error("compare_masks: rasters differ in size");
  std::int64_t tp = 0, fp = 0, fn = 0;
  for (size_t i = 0; i < result.size(); ++i) {
    if (where && !where->pixels()[i]) continue;
    const bool r = result.pixels()[i] != 0, t = truth.pixels()[i] != 0;
    tp += r && t, fp += r && !t, fn += !r && t;
  }
  return scores_from_counts(tp, fp, fn);
}

ClassValidation compare_classes(const Image<std::uint8_t>& result, const Image<std::uint8_t>& truth) {
  if (result.width() != truth.width() || result.height() != truth.height()) throw Error("compare_classes: rasters differ in size");
  std::array<std::int64_t, kBuiltUpClasses> tp{}, fp{}, fn{};
  for (size_t i = 0; i < result.size(); ++i) {
    const int r = result.pixels()[i], t = truth.pixels()[i];
    if (r == t) {
      if (r >= 1 && r <= kBuiltUpClasses) ++tp[r - 1];
      continue;
    }
    if (r >= 1 && r <= kBuiltUpClasses) ++fp[r - 1];
    if (t >= 1 && t <= kBuiltUpClasses) ++fn[t - 1];
  }
  ClassValidation v;
  int contained = 0;
  double sum = 0;
  for (int k = 0; k < kBuiltUpClasses; ++k) {
    v.per_class[k] = scores_from_counts(tp[k], fp[k], fn[k]);
    if (v.per_class[k].contained) ++contained, sum += v.per_class[k].f1;
  }
  v.mean_f1 = contained > 0 ? sum / contained : 0.0;
  return v;
}

}  // namespace hf::lidar
