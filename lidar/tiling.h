// Tile-parallel classification for data that does not fit one run (AHN3 covers the Netherlands): the grid of the
// whole input is cut into nx x ny cores; each tile process reads only the points of its core plus a halo, runs
// the method there and keeps the core; a merge joins components across core borders (union-find over the labels
// of 8-neighbouring border cells) and re-applies the area openings. The merged class raster equals the single
// run's byte for byte (tests/lidar/test_tiling.cpp; scripts/lidar_tiles.slurm runs the tiles as a job array).
//
// Why it is exact: psi(S) at a core cell x depends on the cells s within R_max = t^S max_height_m of x, through
// h(C) of s's building C, which depends on C's cells and on its ground box (C's bounding box grown by the ground
// margin). So a halo of R_max + max_building_m + ground margin (+1 cell) makes every core cell's psi exact. A
// tile checks its assumptions and throws hf::Error rather than return a wrong answer: a building taller than
// max_height_m, or one near the core that is not seen whole with its ground box.
//
// Memory: the merge streams. It reads the tiles twice, one at a time: the first pass joins labels across core
// borders (it keeps one grid-wide row of labels above the current tile row and the column left of the current
// tile), the second writes the classes in bands of rows across the grid's width. It holds one tile, a band, and
// the component table (16 bytes per building and per cluster label of every tile); bench/results/lidar.md has its
// peak RSS. Tiles must form the plan's regular layout (rows of tiles sharing their rows, covering the grid once).
//
// Tile files are binary (magic "HFLTILE1", host byte order with a byte-order mark; written atomically); reading
// checks every size and label and throws hf::Error naming the file and byte offset.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "lidar/built_up_areas.h"

namespace hf::lidar {

struct CellRect {
  int col = 0, row = 0, width = 0, height = 0;  // in the global grid
  bool operator==(const CellRect&) const = default;
};

struct TilePlan {
  Grid grid;               // the whole input's grid
  int tiles_x = 1, tiles_y = 1;
  int halo_cells = 0;
  int count() const { return tiles_x * tiles_y; }
  CellRect core(int tile) const;    // tile = ty * tiles_x + tx
  CellRect window(int tile) const;  // core + halo, clipped to the grid
};

struct TileLimits {
  double max_height_m = 120.0;    // tallest building expected (a Dutch city's towers)
  double max_building_m = 300.0;  // widest building component (cells joined by 8-connectivity) expected
};

// Throws hf::Error for tiles_x or tiles_y < 1, more tiles than cells, or non-positive limits.
TilePlan plan_tiles(const Grid& grid, int tiles_x, int tiles_y, const BuiltUpOptions& options, const TileLimits& limits = {});

// What a tile hands to the merge: its core's S and psi(S), labelled within the core.
struct TileResult {
  Grid grid;
  int tile = 0;
  CellRect core;
  double t_s = 0, cell_m = 0;
  Image<std::int32_t> building_label;  // core-local component of S, -1 outside S
  Image<std::int32_t> cluster_label;   // core-local component of psi(S), -1 outside
  int buildings = 0;
  std::vector<std::int64_t> cluster_cells;  // cells of each core-local cluster inside the core
};

// Runs tile `tile` of `plan` on the files (only points in its window are kept). Throws hf::Error (see above).
TileResult run_tile(const std::vector<std::string>& las_files, const TilePlan& plan, int tile, const BuiltUpOptions& options,
                    const TileLimits& limits = {}, bool progress = false);
// The same on a raster of the tile's window (tests; run_tile rasterises and calls this).
TileResult run_tile_on(const CellRaster& window_raster, const TilePlan& plan, int tile, const BuiltUpOptions& options,
                       const TileLimits& limits = {});

void write_tile(const std::string& path, const TileResult& tile);
TileResult read_tile(const std::string& path);
// Only the fixed header: grid, core, t^S, label counts (cluster_cells has the cluster count's size, all 0; no labels).
TileResult read_tile_header(const std::string& path);

// The classification as a raster with its statistics: what the single run and the merge both produce.
struct BuiltUpRaster {
  Grid grid;
  Mask s;
  Image<std::uint8_t> classes;
  std::array<ClassStatistics, kBuiltUpClasses> stats;
};
BuiltUpRaster built_up_raster(const BuiltUp& b, const Grid& grid);

// Joins the tiles (which must share grid and t^S and cover the grid exactly once) and applies the thresholds.
BuiltUpRaster merge_tiles(const std::vector<TileResult>& tiles, const AreaThresholds& areas);

// The streaming merge of tile files (any order): calls `band(row0, classes, s)` for consecutive bands of at most
// `band_rows` rows (full grid width) from the north edge down, and returns the grid and the statistics. Throws
// hf::Error naming the file for a bad tile, one of another grid or t^S, or tiles that overlap or leave a gap.
struct MergeSummary {
  Grid grid;
  double t_s = 0;
  int tiles = 0;
  std::array<ClassStatistics, kBuiltUpClasses> stats;
};
using MergeBand = std::function<void(int row0, const Image<std::uint8_t>& classes, const Mask& s)>;
MergeSummary merge_tile_files(const std::vector<std::string>& paths, const AreaThresholds& areas, const MergeBand& band,
                              int band_rows = 64);

}  // namespace hf::lidar
