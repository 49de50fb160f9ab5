#include "io/frame_pairing.h"

#include <cmath>

namespace hf {

void StampPairer::offer_depth(double stamp_s, DepthImage depth) {
  depth_.push_back({stamp_s, std::move(depth)});
  if (depth_.size() > history_) {
    depth_.pop_front();
    ++discarded_;
  }
}

void StampPairer::offer_color(double stamp_s, ColorImage color) {
  color_.push_back({stamp_s, std::move(color)});
  if (color_.size() > history_) {
    color_.pop_front();
    ++discarded_;
  }
}

std::optional<CapturedFrame> StampPairer::take() {
  for (size_t d = 0; d < depth_.size(); ++d) {
    size_t best = color_.size();
    double best_dt = max_difference_s_;
    for (size_t c = 0; c < color_.size(); ++c) {
      const double dt = std::abs(depth_[d].stamp_s - color_[c].stamp_s);
      if (dt <= best_dt) {
        best_dt = dt;
        best = c;
      }
    }
    if (best == color_.size()) continue;
    CapturedFrame f;
    f.timestamp_s = color_[best].stamp_s;
    f.depth = std::move(depth_[d].image);
    f.color = std::move(color_[best].image);
    discarded_ += d + best;
    depth_.erase(depth_.begin(), depth_.begin() + long(d) + 1);
    color_.erase(color_.begin(), color_.begin() + long(best) + 1);
    return f;
  }
  return std::nullopt;
}

}  // namespace hf
