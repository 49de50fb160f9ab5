// Evaluation thresholding (Kubásková section 3.2) and the truncation of section 3.1.3.
//   normalise_percent: eq. 10, w_i <- 100 w_i / |w_max| with |w_max| the largest |w| over valid vertices, so
//     values lie in [-100, 100] % (signed evaluations keep their sign). All zero when |w_max| = 0 (a plane).
//   threshold: Omega_i = 1 for valid vertices with w_i in [a, b], the feature set F_s.
//   truncate_top_percent: the `percent` % of valid vertices with the highest w get the highest value among the
//     others, so a few spikes (slivers, scan noise) do not flatten eq. 10's scale.
// Vertices with valid[i] == 0 never become features and are left at 0 by normalise_percent.
#pragma once

#include <cstdint>
#include <vector>

namespace hf::head {

using VertexMask = std::vector<std::uint8_t>;  // 1 = in the set, one entry per vertex

std::vector<float> normalise_percent(const std::vector<float>& w, const VertexMask& valid);
VertexMask threshold(const std::vector<float>& w, const VertexMask& valid, float a, float b);
void truncate_top_percent(std::vector<float>& w, const VertexMask& valid, double percent);
// Mean of w over valid vertices with mask[i] != 0 (mask empty: all valid vertices); 0 when there are none.
double masked_mean(const std::vector<float>& w, const VertexMask& valid, const VertexMask& mask = {});

}  // namespace hf::head
