#include "head/thresholding.h"

#include <algorithm>
#include <cmath>

namespace hf::head {

std::vector<float> normalise_percent(const std::vector<float>& w, const VertexMask& valid) {
  double w_max = 0.0;
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i]) w_max = std::max(w_max, std::abs(static_cast<double>(w[i])));
  std::vector<float> out(w.size(), 0.0f);
  if (!(w_max > 0.0)) return out;
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i]) out[i] = static_cast<float>(100.0 * w[i] / w_max);
  return out;
}

VertexMask threshold(const std::vector<float>& w, const VertexMask& valid, float a, float b) {
  VertexMask out(w.size(), 0);
  for (size_t i = 0; i < w.size(); ++i) out[i] = valid[i] && w[i] >= a && w[i] <= b;
  return out;
}

void truncate_top_percent(std::vector<float>& w, const VertexMask& valid, double percent) {
  if (!(percent > 0.0)) return;
  std::vector<size_t> order;
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i]) order.push_back(i);
  const size_t cut = std::min(order.size(), static_cast<size_t>(std::llround(order.size() * std::min(percent, 100.0) / 100.0)));
  if (cut == 0 || cut == order.size()) return;
  std::nth_element(order.begin(), order.begin() + static_cast<long>(cut), order.end(),
                   [&](size_t x, size_t y) { return w[x] > w[y]; });
  // order[0, cut) are the top `cut`; the largest of the rest is order[cut] after nth_element.
  const float ceiling = w[order[cut]];
  for (size_t k = 0; k < cut; ++k) w[order[k]] = ceiling;
}

double masked_mean(const std::vector<float>& w, const VertexMask& valid, const VertexMask& mask) {
  double sum = 0.0;
  long count = 0;
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i] && (mask.empty() || mask[i])) {
      sum += w[i];
      ++count;
    }
  return count > 0 ? sum / static_cast<double>(count) : 0.0;
}

}  // namespace hf::head
