#include "head/automatic_detection.h"

namespace hf::head {

AreaFeatures detect_area_features(const ImportantAreas& areas, const VertexCurvatures& discrete,
                                  const VertexCurvatures& mls, double mls_truncate_percent) {
  const size_t n = areas.label.size();
  AreaFeatures out;
  out.features.assign(n, 0);
  std::vector<float> lips_mean = discrete.mean;
  truncate_top_percent(lips_mean, discrete.valid, 5.0);
  std::vector<float> eyes_k = mls.k_max, ears_h = mls.mean;
  truncate_top_percent(eyes_k, mls.valid, mls_truncate_percent);
  truncate_top_percent(ears_h, mls.valid, mls_truncate_percent);
  const std::vector<float> eyes = normalise_percent(eyes_k, mls.valid);
  const std::vector<float> ears = normalise_percent(ears_h, mls.valid);
  const std::vector<float> lips = normalise_percent(lips_mean, discrete.valid);
  const std::vector<float> nose = normalise_percent(discrete.k_max, discrete.valid);
  for (int a = 1; a < kAreaCount; ++a) {
    const Area area = static_cast<Area>(a);
    const bool eye = area == Area::eye_left || area == Area::eye_right;
    const bool ear = area == Area::ear_left || area == Area::ear_right;
    const std::vector<float>& w = eye ? eyes : (ear ? ears : (area == Area::lips ? lips : nose));
    const VertexMask& valid = eye || ear ? mls.valid : discrete.valid;
    VertexMask in_area(n, 0);
    for (size_t i = 0; i < n; ++i) in_area[i] = areas.label[i] == area;
    const double t = masked_mean(w, valid, in_area);
    out.threshold_percent[a] = t;
    for (size_t i = 0; i < n; ++i)
      if (in_area[i] && valid[i] && w[i] >= t) out.features[i] = 1;
  }
  return out;
}

}  // namespace hf::head
