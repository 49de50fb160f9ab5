#include "registration/pixel_selection.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"

namespace hf {

void PixelSelectionOptions::validate() const {
  const int m = int(mode);
  if (m < 0 || m > 2) throw Error("registration options: row_selection must be 0 (all), 1 (importance) or 2 (uniform)");
  if (tile_px < 2 || tile_px > 64 || (tile_px & (tile_px - 1)) != 0)
    throw Error("registration options: row_selection_tile_px must be a power of two in [2, 64], got " +
                std::to_string(tile_px));
  if (budget_per_tile < 1 || budget_per_tile > tile_px * tile_px)
    throw Error("registration options: row_selection_budget must be in [1, row_selection_tile_px^2], got " +
                std::to_string(budget_per_tile));
  if (!(std::isfinite(depth_edge_weight) && depth_edge_weight >= 0.0f))
    throw Error("registration options: row_selection_depth_edge_weight must be finite and >= 0");
  if (levels < 1 || levels > 8) throw Error("registration options: row_selection_levels must be in [1, 8]");
}

int dither_rank(int x, int y, int tile_px) {
  // Bayer's recursion read from the lowest coordinate bit up: bit b of (x ^ y) and of y become the rank's two bits
  // of weight 4^(n - 1 - b), so the coarsest lattice comes first.
  int rank = 0;
  for (int b = 1; b < tile_px; b <<= 1) rank = (rank << 2) | (((x ^ y) & b) ? 2 : 0) | ((y & b) ? 1 : 0);
  return rank;
}

Image<float> pixel_importance(const FramePyramidLevel& level, float depth_edge_weight) {
  const VertexMap& v = level.vertices;
  const int W = v.width(), H = v.height();
  Image<float> score(W, H, 0.0f);
  const bool intensity = level.has_intensity() && level.grad_x.size() == v.size() && level.grad_y.size() == v.size();
  tbb::parallel_for(tbb::blocked_range<int>(0, H), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y != rows.end(); ++y)
      for (int x = 0; x < W; ++x) {
        const hf_float4& p = v(x, y);
        if (p.w == 0.0f || !(p.z > 0.0f)) continue;
        float edge = 0.0f;
        auto step = [&](int qx, int qy) {
          if (qx < 0 || qy < 0 || qx >= W || qy >= H) return;
          const hf_float4& q = v(qx, qy);
          if (q.w != 0.0f) edge = std::max(edge, std::fabs(q.z - p.z) / p.z);
        };
        step(x - 1, y), step(x + 1, y), step(x, y - 1), step(x, y + 1);
        float s = depth_edge_weight * std::min(edge, 1.0f);
        if (intensity) s += std::hypot(level.grad_x(x, y), level.grad_y(x, y));
        score(x, y) = std::isfinite(s) ? s : 0.0f;
      }
  });
  return score;
}

Image<std::uint8_t> select_pixels(const FramePyramidLevel& level, const PixelSelectionOptions& options) {
  options.validate();
  const VertexMap& v = level.vertices;
  const int W = v.width(), H = v.height(), T = options.tile_px, B = options.budget_per_tile;
  Image<std::uint8_t> mask(W, H, 0);
  if (!options.enabled()) {
    for (size_t i = 0; i < v.size(); ++i) mask.pixels()[i] = v.pixels()[i].w != 0.0f ? 1 : 0;
    return mask;
  }
  const bool by_importance = options.mode == PixelSelectionMode::importance;
  const Image<float> score = by_importance ? pixel_importance(level, options.depth_edge_weight) : Image<float>();
  const int TW = (W + T - 1) / T, TH = (H + T - 1) / T;
  tbb::parallel_for(tbb::blocked_range<int>(0, TW * TH), [&](const tbb::blocked_range<int>& tiles) {
    struct Candidate {
      float score;
      int rank, x, y;
    };
    std::vector<Candidate> c;
    c.reserve(size_t(T) * T);
    for (int t = tiles.begin(); t != tiles.end(); ++t) {
      const int x0 = (t % TW) * T, y0 = (t / TW) * T;
      c.clear();
      for (int y = y0; y < std::min(y0 + T, H); ++y)
        for (int x = x0; x < std::min(x0 + T, W); ++x)
          if (v(x, y).w != 0.0f)
            c.push_back({by_importance ? score(x, y) : 0.0f, dither_rank(x - x0, y - y0, T), x, y});
      if (int(c.size()) > B) {
        // Higher importance first, then the lower dither rank (unique within the tile: a strict total order).
        std::nth_element(c.begin(), c.begin() + B, c.end(), [](const Candidate& a, const Candidate& b) {
          return a.score != b.score ? a.score > b.score : a.rank < b.rank;
        });
        c.resize(size_t(B));
      }
      for (const Candidate& k : c) mask(k.x, k.y) = 1;
    }
  });
  return mask;
}

void apply_pixel_selection(const Image<std::uint8_t>& mask, VertexMap* vertices) {
  if (mask.width() != vertices->width() || mask.height() != vertices->height())
    throw Error("pixel selection: the mask is " + std::to_string(mask.width()) + "x" + std::to_string(mask.height()) +
                " but the vertex map " + std::to_string(vertices->width()) + "x" + std::to_string(vertices->height()));
  for (size_t i = 0; i < mask.size(); ++i)
    if (mask.pixels()[i] == 0) vertices->pixels()[i] = hf_invalid4();
}

}  // namespace hf
