// The classification of built-up areas of Cvirn section 4, as stages:
//   rasterise (grid.h: S of eq. 5, per-cell tops and ground) -> components C_i (8-connected) -> heights (eq. 6,
//   above local ground) -> psi = delta^{t^S h}(S) -> differential profile of second-generation area openings.
#pragma once

#include <string>
#include <vector>

#include "lidar/building_heights.h"
#include "lidar/differential_profile.h"
#include "lidar/grid.h"

namespace hf::lidar {

struct BuiltUpOptions {
  double cell_m = 0.5;  // r
  double t_s = 2.0;     // t^S: structuring-element radius per metre of building height (Table 2's best for towns)
  AreaThresholds areas;
  HeightOptions heights;
  PointClasses classes;
};
// Throws hf::Error naming the bad option.
void validate(const BuiltUpOptions& o);

struct BuiltUp {
  Mask s;                      // building cells (eq. 5)
  Components buildings;        // C_i
  std::vector<double> heights_m;  // h(C_i)
  Image<float> height_m;       // h per cell (eq. 6)
  Mask psi_s;                  // delta^{t^S h}(S)
  Profile profile;             // classes and per-class statistics
};

// Stages after rasterisation. psi and the profile depend on t^S; buildings and heights do not.
BuiltUp classify_built_up(const CellRaster& raster, const BuiltUpOptions& options);
// Re-runs psi and the profile for another t^S (the sensitivity analysis), reusing S, C_i and heights.
void reclassify(BuiltUp& b, double t_s, const AreaThresholds& areas, double cell_m);

// The grid over the union of the files' header bounding boxes (headers only are read). Throws hf::Error naming the
// files when the box is not valid or the grid too large (sizes printed short).
Grid grid_of_files(const std::vector<std::string>& las_files, double cell_m);

// What rasterise_files does with a point outside `grid`: skip it (a tile's window), or refuse the file (a grid from
// grid_of_files covers every header's box, so such a point proves its header's box wrong and the run would
// silently lose it: "FILE: 14408 of 14410 points lie outside the header's bounding box ...").
enum class OutsideGrid { skip, refuse };

// Streams every file's points into a raster on `grid`; `progress` draws a bar. Throws hf::Error as LasReader, and
// with OutsideGrid::refuse for a file with points outside `whole` (default: `grid` itself; a tile passes the grid
// its window belongs to, so the window's own edges skip points and only the header's lie refuses), counted over
// the whole file.
CellRaster rasterise_files(const std::vector<std::string>& las_files, const Grid& grid, const PointClasses& classes,
                           bool progress = false, OutsideGrid outside = OutsideGrid::skip,
                           const Grid* whole = nullptr);

}  // namespace hf::lidar
