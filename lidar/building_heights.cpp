#include "lidar/building_heights.h"

#include <algorithm>
#include <cmath>

namespace hf::lidar {
namespace {

// Summed-area table with a zero row and column in front: S(x, y) = sum of v over [0, x) x [0, y).
template <class T, class Acc>
std::vector<Acc> summed_area(const Image<T>& v) {
  const int w = v.width(), h = v.height();
  std::vector<Acc> s(size_t(w + 1) * (h + 1), Acc(0));
  for (int y = 0; y < h; ++y) {
    Acc row = 0;
    for (int x = 0; x < w; ++x) {
      row += static_cast<Acc>(v(x, y));
      s[size_t(y + 1) * (w + 1) + x + 1] = s[size_t(y) * (w + 1) + x + 1] + row;
    }
  }
  return s;
}

template <class Acc>
Acc box_sum(const std::vector<Acc>& s, int w, int x0, int y0, int x1, int y1) {  // inclusive box
  const auto at = [&](int x, int y) { return s[size_t(y) * (w + 1) + x]; };
  return at(x1 + 1, y1 + 1) - at(x0, y1 + 1) - at(x1 + 1, y0) + at(x0, y0);
}

}  // namespace

std::vector<double> building_heights(const CellRaster& raster, const Components& buildings, const HeightOptions& options) {
  const int w = raster.grid.width, h = raster.grid.height;
  const auto sum_z = summed_area<std::int64_t, std::int64_t>(raster.ground_sum_mm);
  const auto count = summed_area<std::int32_t, std::int64_t>(raster.ground_count);
  const int margin = static_cast<int>(std::ceil(std::max(0.0, options.ground_margin_m) / raster.grid.cell_m));

  std::vector<double> top(static_cast<size_t>(buildings.count), -1e300);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (const int id = buildings.label(x, y); id >= 0) top[id] = std::max(top[id], double(raster.building_top_z(x, y)));

  std::vector<double> heights(static_cast<size_t>(buildings.count), 0.0);
  for (int id = 0; id < buildings.count; ++id) {
    const int x0 = std::max(0, buildings.min_col[id] - margin), x1 = std::min(w - 1, buildings.max_col[id] + margin);
    const int y0 = std::max(0, buildings.min_row[id] - margin), y1 = std::min(h - 1, buildings.max_row[id] + margin);
    const std::int64_t n = box_sum(count, w, x0, y0, x1, y1);
    double ground;
    if (n > 0) {
      ground = double(box_sum(sum_z, w, x0, y0, x1, y1)) / double(n) / 1000.0;
    } else {
      ground = top[id];  // at worst the building itself: height 0
      for (int y = y0; y <= y1; ++y)
        for (int x = x0; x <= x1; ++x)
          if (raster.any_points(x, y)) ground = std::min(ground, double(raster.lowest_z(x, y)));
    }
    const double height = top[id] - ground;
    heights[id] = std::isfinite(height) ? std::max(0.0, height) : 0.0;
  }
  return heights;
}

Image<float> height_raster(const Components& buildings, const std::vector<double>& heights) {
  Image<float> out(buildings.label.width(), buildings.label.height(), 0.0f);
  for (size_t i = 0; i < out.size(); ++i)
    if (const int id = buildings.label.pixels()[i]; id >= 0) out.pixels()[i] = static_cast<float>(heights[id]);
  return out;
}

}  // namespace hf::lidar
