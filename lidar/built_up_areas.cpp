#include "lidar/built_up_areas.h"

#include <cmath>
#include <limits>
#include <optional>

#include "core/error.h"
#include "core/number_text.h"
#include "core/progress.h"
#include "io/las.h"
#include "lidar/variant_dilation.h"

namespace hf::lidar {

void validate(const BuiltUpOptions& o) {
  if (!(std::isfinite(o.cell_m) && o.cell_m > 0)) throw Error("cell size must be positive (metres)");
  if (!(std::isfinite(o.t_s) && o.t_s >= 0)) throw Error("t^S must be finite and >= 0");
  if (!(std::isfinite(o.heights.ground_margin_m) && o.heights.ground_margin_m >= 0)) throw Error("ground margin must be >= 0 (metres)");
  validate(o.areas);
}

void reclassify(BuiltUp& b, double t_s, const AreaThresholds& areas, double cell_m) {
  b.psi_s = variant_dilation(b.s, clustering_radii(b.height_m, t_s, cell_m));
  b.profile = differential_profile(b.s, b.psi_s, areas, cell_m);
}

BuiltUp classify_built_up(const CellRaster& raster, const BuiltUpOptions& options) {
  validate(options);
  BuiltUp b;
  b.s = raster.building;
  b.buildings = connected_components(b.s);
  b.heights_m = building_heights(raster, b.buildings, options.heights);
  b.height_m = height_raster(b.buildings, b.heights_m);
  reclassify(b, options.t_s, options.areas, raster.grid.cell_m);
  return b;
}

namespace {

// The inputs named in a message: the first file, and how many more.
std::string files_for_message(const std::vector<std::string>& files) {
  if (files.empty()) return "(no files)";
  return files.size() == 1 ? files[0] : files[0] + " and " + std::to_string(files.size() - 1) + " more";
}

}  // namespace

Grid grid_of_files(const std::vector<std::string>& files, double cell_m) {
  if (files.empty()) throw Error("no LAS input given");
  double lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  double hi[2] = {-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
  for (const std::string& f : files) {
    const LasReader reader(f);
    const LasHeader& h = reader.header();
    if (h.point_count == 0) continue;
    for (int k = 0; k < 2; ++k) {
      if (!(std::isfinite(h.min[k]) && std::isfinite(h.max[k]) && h.min[k] <= h.max[k]))
        throw Error(f + ": the header's bounding box is not valid");
      lo[k] = std::min(lo[k], h.min[k]), hi[k] = std::max(hi[k], h.max[k]);
    }
  }
  if (lo[0] > hi[0]) throw Error(files_for_message(files) + ": the LAS inputs hold no points");
  try {
    return grid_over(lo[0], lo[1], hi[0], hi[1], cell_m);
  } catch (const Error& e) {
    throw Error(files_for_message(files) + ": " + e.what());
  }
}

namespace {

// Usable points (CellRaster::add's filter) of `pts` that lie outside `grid`.
std::uint64_t las_points_outside_grid(const std::vector<LasPoint>& pts, const Grid& grid) {
  std::uint64_t n = 0;
  for (const LasPoint& p : pts) {
    if (p.withheld || !std::isfinite(p.x) || !std::isfinite(p.y) || !(std::abs(p.z) <= 1e6)) continue;
    int c, r;
    if (!grid.cell_of(p.x, p.y, c, r)) ++n;
  }
  return n;
}

}  // namespace

CellRaster rasterise_files(const std::vector<std::string>& files, const Grid& grid, const PointClasses& classes,
                           bool progress, OutsideGrid outside, const Grid* whole) {
  CellRaster raster(grid);
  std::uint64_t total = 0;
  for (const std::string& f : files) total += LasReader(f).header().point_count;
  std::optional<Progress> bar;
  if (progress) bar.emplace("reading points", static_cast<long>(std::min<std::uint64_t>(total, std::numeric_limits<long>::max())));
  std::uint64_t done = 0;
  std::vector<LasPoint> chunk;
  for (const std::string& f : files) {
    LasReader reader(f);
    const std::uint64_t outside_before = raster.outside;
    std::uint64_t outside_whole = 0;
    while (reader.read_chunk(chunk, 1 << 18)) {
      raster.add(chunk, classes);
      if (whole && outside == OutsideGrid::refuse) outside_whole += las_points_outside_grid(chunk, *whole);
      done += chunk.size();
      if (bar) bar->update(static_cast<long>(done));
    }
    const std::uint64_t lost = whole ? outside_whole : raster.outside - outside_before;
    if (outside == OutsideGrid::refuse && lost > 0) {
      const LasHeader& h = reader.header();
      throw Error(f + ": " + std::to_string(lost) + " of " + std::to_string(h.point_count) +
                  " points lie outside the header's bounding box (x " + number_for_message(h.min[0]) + ".." +
                  number_for_message(h.max[0]) + ", y " + number_for_message(h.min[1]) + ".." +
                  number_for_message(h.max[1]) + "), so the grid built from it cannot hold them; the header is "
                  "wrong: rewrite its box (e.g. `lasinfo -repair_bb`) and rerun");
    }
  }
  if (bar) bar->finish();
  return raster;
}

}  // namespace hf::lidar
