#include "lidar/grid.h"

#include <cmath>

#include "core/error.h"
#include "core/number_text.h"

namespace hf::lidar {

bool Grid::cell_of(double x, double y, int& col, int& row) const {
  const double c = std::floor(x / cell_m) - static_cast<double>(col0);
  const double r = static_cast<double>(row0 - 1) - std::floor(y / cell_m);
  if (!(c >= 0 && c < width && r >= 0 && r < height)) return false;
  col = static_cast<int>(c);
  row = static_cast<int>(r);
  return true;
}

Grid grid_over(double min_x, double min_y, double max_x, double max_y, double cell_m) {
  if (!(std::isfinite(cell_m) && cell_m > 0)) throw Error("grid: cell size must be positive and finite");
  if (!(std::isfinite(min_x) && std::isfinite(min_y) && std::isfinite(max_x) && std::isfinite(max_y)) || max_x < min_x ||
      max_y < min_y)
    throw Error("grid: the bounding box is empty or not finite");
  Grid g;
  g.cell_m = cell_m;
  const double i0 = std::floor(min_x / cell_m), i1 = std::floor(max_x / cell_m);
  const double j0 = std::floor(min_y / cell_m), j1 = std::floor(max_y / cell_m);
  const double w = i1 - i0 + 1, h = j1 - j0 + 1;
  if (std::abs(i0) > 1e15 || std::abs(j1) > 1e15 || w * h > 2147483647.0)
    throw Error("grid: " + number_for_message(w) + " x " + number_for_message(h) +
                " cells is too many; tile the input");
  g.col0 = static_cast<std::int64_t>(i0);
  g.row0 = static_cast<std::int64_t>(j1) + 1;
  g.width = static_cast<int>(w);
  g.height = static_cast<int>(h);
  return g;
}

namespace {
// About 30 bytes per cell: 4e8 cells is 12 GB, beyond which a run should be tiled rather than die in new.
const Grid& checked(const Grid& g) {
  if (g.width <= 0 || g.height <= 0) throw Error("grid: empty");
  if (double(g.width) * g.height > 4e8)
    throw Error("grid: " + std::to_string(g.width) + " x " + std::to_string(g.height) +
                " cells need more than 12 GB; run it tiled (--tiles) or with a larger --cell-m");
  return g;
}
}  // namespace

CellRaster::CellRaster(const Grid& g)
    : grid(checked(g)),
      building(g.width, g.height, 0),
      building_top_z(g.width, g.height, 0.0f),
      ground_sum_mm(g.width, g.height, 0),
      ground_count(g.width, g.height, 0),
      lowest_z(g.width, g.height, 0.0f),
      any_points(g.width, g.height, 0) {}

void CellRaster::add(const std::vector<LasPoint>& pts, const PointClasses& classes) {
  for (const LasPoint& p : pts) {
    // Withheld points are not to be used; positions beyond any terrain (|z| > 1e6 m) are corrupt files.
    if (p.withheld || !std::isfinite(p.x) || !std::isfinite(p.y) || !(std::abs(p.z) <= 1e6)) continue;
    int c, r;
    if (!grid.cell_of(p.x, p.y, c, r)) {
      ++outside;
      continue;
    }
    ++points;
    const auto z = static_cast<float>(p.z);
    if (!any_points(c, r) || z < lowest_z(c, r)) lowest_z(c, r) = z;
    any_points(c, r) = 1;
    if (classes.building.count(p.classification)) {
      if (!building(c, r) || z > building_top_z(c, r)) building_top_z(c, r) = z;
      building(c, r) = 1;
    } else if (classes.ground.count(p.classification)) {
      ground_sum_mm(c, r) += std::llround(p.z * 1000.0);
      ++ground_count(c, r);
    }
  }
}

}  // namespace hf::lidar
