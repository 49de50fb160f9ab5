#include "lidar/variant_dilation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"

namespace hf::lidar {
namespace {

// Largest half-width d >= 0 with d^2 + dy^2 <= r2 (integers, so the disc does not depend on sqrt's rounding).
int half_width(double r2, int dy) {
  const double rest = r2 - double(dy) * dy;
  auto d = static_cast<long long>(std::sqrt(std::max(0.0, rest)));
  while (double(d + 1) * double(d + 1) <= rest) ++d;
  while (d > 0 && double(d) * double(d) > rest) --d;
  return static_cast<int>(d);
}

}  // namespace

Mask variant_dilation(const Mask& mask, const Image<float>& radius_cells) {
  const int w = mask.width(), h = mask.height();
  if (radius_cells.width() != w || radius_cells.height() != h) throw Error("variant_dilation: radius raster size differs from the mask");
  const auto radius = [&](int x, int y) { return std::max(0.0f, radius_cells(x, y)); };
  // diff(x, y) += 1 at a span's first cell and -= 1 one past its last; a prefix sum per row counts covering discs.
  std::vector<std::int32_t> diff(size_t(w + 1) * h, 0);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!mask(x, y)) continue;
      const float r = radius(x, y);
      const auto covers = [&](int nx, int ny) { return nx >= 0 && ny >= 0 && nx < w && ny < h && mask(nx, ny) && radius(nx, ny) >= r; };
      if (covers(x - 1, y) && covers(x + 1, y) && covers(x, y - 1) && covers(x, y + 1)) {
        ++diff[size_t(y) * (w + 1) + x];  // s itself
        --diff[size_t(y) * (w + 1) + x + 1];
        continue;
      }
      const double r2 = double(r) * double(r);
      const int reach = static_cast<int>(std::floor(double(r)));
      for (int dy = -reach; dy <= reach; ++dy) {
        const int yy = y + dy;
        if (yy < 0 || yy >= h) continue;
        const int d = half_width(r2, dy);
        const int x0 = std::max(0, x - d), x1 = std::min(w - 1, x + d);
        if (x0 > x1) continue;
        ++diff[size_t(yy) * (w + 1) + x0];
        --diff[size_t(yy) * (w + 1) + x1 + 1];
      }
    }
  Mask out(w, h, 0);
  for (int y = 0; y < h; ++y) {
    std::int32_t depth = 0;
    for (int x = 0; x < w; ++x) {
      depth += diff[size_t(y) * (w + 1) + x];
      out(x, y) = depth > 0 ? 1 : 0;
    }
  }
  return out;
}

Image<float> clustering_radii(const Image<float>& height_m, double t_s, double cell_m) {
  if (!(std::isfinite(t_s) && t_s >= 0)) throw Error("clustering operator: t^S must be finite and >= 0");
  Image<float> r(height_m.width(), height_m.height(), 0.0f);
  for (size_t i = 0; i < r.size(); ++i) r.pixels()[i] = static_cast<float>(t_s * height_m.pixels()[i] / cell_m);
  return r;
}

}  // namespace hf::lidar
