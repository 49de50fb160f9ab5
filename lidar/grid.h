// The grid G of Cvirn section 4: square cells of resolution r = cell_m over the points' bounding box, and what
// each cell g_i learns from its points P_{g_i} (the points nearer to g_i's centre than to any other, i.e. those
// inside the cell).
//
// Frame: the input's projected CRS in metres (EPSG:28992 for AHN3). Cells are the squares
// [i r, (i+1) r) x [j r, (j+1) r) of the whole plane (i = floor(x / r), j = floor(y / r)); a Grid is a window of
// them: cell (col, row) is i = col0 + col, j = row0 - 1 - row, so row 0 is the north edge and rasters are
// north-up like GeoTIFF and PNG. Every window (a tile, another file's extent) computes a point's cell with the
// same floor(x / r), so windows agree on every cell bit for bit.
#pragma once

#include <cstdint>
#include <set>
#include <vector>

#include "core/image.h"
#include "io/las.h"

namespace hf::lidar {

struct Grid {
  double cell_m = 0.5;                // r; 0.5 m is the paper's "usually sufficient" value
  std::int64_t col0 = 0, row0 = 0;    // west edge = col0 r, north edge = row0 r (metres)
  int width = 0, height = 0;          // cells

  double west() const { return static_cast<double>(col0) * cell_m; }
  double north() const { return static_cast<double>(row0) * cell_m; }
  // The sub-window of `w` x `h` cells whose top-left cell is (col, row) of this grid (may extend outside it).
  Grid window(int col, int row, int w, int h) const { return {cell_m, col0 + col, row0 - row, w, h}; }

  // Cell of a point; false when it lies outside the grid.
  bool cell_of(double x, double y, int& col, int& row) const;
  double cell_area_m2() const { return cell_m * cell_m; }
  bool operator==(const Grid&) const = default;
};

// The grid over a bounding box (metres). Throws hf::Error for a non-positive or non-finite cell size, an empty
// or non-finite box, or one over 2^31 cells.
Grid grid_over(double min_x, double min_y, double max_x, double max_y, double cell_m);

// Which ASPRS classes mean what; defaults are the standard codes AHN3 uses.
struct PointClasses {
  std::set<int> building = {6};
  std::set<int> ground = {2};
};

// Per-cell summaries of the points, accumulated chunk by chunk (streaming; memory is per cell, not per point).
// Withheld points are ignored.
struct CellRaster {
  Grid grid;
  Image<std::uint8_t> building;     // S of eq. 5: 1 where a building-class point falls in the cell
  Image<float> building_top_z;      // highest building point of the cell (metres; valid where building = 1)
  // Sum of the ground-class points' z in whole millimetres: integer sums do not depend on summation order, so a
  // tile and the single run derive bit-identical ground levels.
  Image<std::int64_t> ground_sum_mm;
  Image<std::int32_t> ground_count; // number of ground-class points
  Image<float> lowest_z;            // lowest point of any class (valid where any_points = 1)
  Image<std::uint8_t> any_points;
  std::uint64_t points = 0;         // points that fell in the grid
  std::uint64_t outside = 0;        // usable points (not withheld, finite) that fell outside it

  CellRaster() = default;
  explicit CellRaster(const Grid& g);  // throws hf::Error beyond 4e8 cells (about 12 GB): tile such inputs
  void add(const std::vector<LasPoint>& points, const PointClasses& classes = {});
};

}  // namespace hf::lidar
