// `hashfusion lidar`: built-up-area classification of LiDAR point clouds (lidar/built_up_areas.h; Cvirn), single
// run, one tile of a tiled run, or the merge of a tiled run (lidar/tiling.h). Writes classes.png (with a legend),
// classes.tif (GeoTIFF), buildings.png, report.md and report.json to --out.
#include <CLI/CLI.hpp>
#include <sys/stat.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "core/output_transaction.h"
#include "io/las.h"
#include "lidar/class_raster_io.h"
#include "lidar/footprints.h"
#include "lidar/report.h"
#include "lidar/synthetic_settlements.h"

namespace hf::apps {
namespace {

struct LidarArgs {
  std::vector<std::string> inputs;
  std::string out;
  double cell_m = 0.5, t_s = 2.0, ground_margin_m = 10.0;
  std::string areas, sweep, tiles, merge, footprints, footprint_layer;
  int tile = -1, epsg = 0;
  double max_height_m = 120.0, max_building_m = 300.0;
  std::string shown_out;  // --out as the user gave it, for messages (out is the transaction's private folder)
};

// Every file a lidar run (single or merge) writes into --out. Tile tasks (--tile K) write only tile_K.hflt, into a
// folder they share by design, and take no transaction.
const std::vector<std::string>& lidar_output_names() {
  static const std::vector<std::string> names = {"classes.png", "classes.tif", "buildings.png",
                                                 "report.json", "report.md",   "synthetic.las"};
  return names;
}

// What the lidar run that last wrote `out` wrote there: the names its report.json lists under "outputs" (among
// the names a lidar run writes), or all of those for a lidar report from before that list; none for a folder
// without a lidar report.json (a user's folder, another command's report), so every file there is carried over.
std::function<bool(const std::string&)> previous_lidar_run_wrote(const std::string& out) {
  std::set<std::string> names;
  nlohmann::json j;
  if (read_previous_manifest(out + "/report.json", &j) && j.is_object() && j.contains("parameters") &&
      j.contains("grid") && j.contains("classes")) {
    const auto& known = lidar_output_names();
    if (j.contains("outputs") && j["outputs"].is_array()) {
      for (const nlohmann::json& name : j["outputs"])
        if (name.is_string() && std::count(known.begin(), known.end(), name.get<std::string>()) > 0)
          names.insert(name.get<std::string>());
    } else {
      names.insert(known.begin(), known.end());
    }
  }
  return [names](const std::string& name) { return names.count(name) > 0; };
}

// The largest t^S taken (--t-m-per-m, --sweep-t-m-per-m): radii of a kilometre per metre of height already cover any grid;
// beyond, the radius in cells overflows (1e308 failed deep in the clustering operator).
constexpr double kMaxTMPerM = 1000.0;

std::vector<double> numbers(const std::string& text, const std::string& option) {
  std::vector<double> v;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    try {
      size_t used = 0;
      v.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw Error(option + ": '" + item + "' is not a number");
    }
  }
  return v;
}

// --sweep-t-m-per-m's values, each in --t-m-per-m's range.
std::vector<double> sweep_values(const std::string& text) {
  std::vector<double> v = numbers(text, "--sweep-t-m-per-m");
  for (double t : v)
    if (!(t >= 0 && t <= kMaxTMPerM))
      throw Error("--sweep-t-m-per-m: expected 0.." + number_for_message(kMaxTMPerM) + " m per m, got " + number_for_message(t));
  return v;
}

lidar::BuiltUpOptions options_of(const LidarArgs& a) {
  lidar::BuiltUpOptions o;
  o.cell_m = a.cell_m, o.t_s = a.t_s;
  o.heights.ground_margin_m = a.ground_margin_m;
  if (!a.areas.empty()) {
    const auto v = numbers(a.areas, "--areas-m2");
    if (v.size() != 3) throw Error("--areas-m2: expected a1,a2,a3 (m^2)");
    o.areas = {v[0], v[1], v[2]};
  }
  lidar::validate(o);
  return o;
}

std::pair<int, int> tile_counts(const std::string& text) {
  const auto v = numbers(text, "--tiles");
  if (v.size() != 2 || v[0] < 1 || v[1] < 1 || v[0] != int(v[0]) || v[1] != int(v[1])) throw Error("--tiles: expected NX,NY (whole numbers >= 1)");
  return {int(v[0]), int(v[1])};
}

// Rasters and tables of a finished classification (single or merged), with footprint / class validation.
std::string write_outputs(const LidarArgs& a, lidar::Report& report, const lidar::BuiltUpRaster& r, const lidar::Mask* footprint_truth,
                   const lidar::Mask* coverage) {
  report.raster = &r;
  if (footprint_truth) report.building_mask = lidar::compare_masks(r.s, *footprint_truth, coverage);
  lidar::write_class_png(a.out + "/classes.png", r.classes);
  lidar::write_class_geotiff(a.out + "/classes.tif", r.classes, r.grid, report.epsg);
  lidar::write_mask_png(a.out + "/buildings.png", r.s, footprint_truth);
  lidar::write_report(a.out, report);
  return lidar::report_markdown(report);
}

// The merge of a tiled run, streamed (lidar/tiling.h): bands of rows go straight into classes.png, classes.tif
// and buildings.png (and into the footprint comparison), so the whole grid is never in memory.
std::string run_merge(const LidarArgs& a, const lidar::BuiltUpOptions& o, lidar::Report& report) {
  std::vector<std::string> paths;
  for (const auto& e : std::filesystem::directory_iterator(a.merge))
    if (e.path().extension() == ".hflt") paths.push_back(e.path().string());
  if (paths.empty()) throw Error(a.merge + ": no tile_*.hflt files");
  std::sort(paths.begin(), paths.end());
  const lidar::TileResult first = lidar::read_tile_header(paths[0]);
  const lidar::Grid grid = first.grid;
  report.options.t_s = first.t_s, report.options.cell_m = first.cell_m;
  report.tiles = std::to_string(paths.size()) + " tiles";
  report.epsg = a.epsg;
  report.inputs = {a.merge};
  std::vector<lidar::Polygon> polygons;
  if (!a.footprints.empty()) polygons = lidar::read_footprints(a.footprints, a.footprint_layer, &grid);
  std::int64_t tp = 0, fp = 0, fn = 0;
  lidar::MergeSummary summary;
  write_path_atomically(a.out + "/classes.png", [&](const std::string& png_tmp) {
    write_path_atomically(a.out + "/classes.tif", [&](const std::string& tif_tmp) {
      write_path_atomically(a.out + "/buildings.png", [&](const std::string& mask_tmp) {
        lidar::ClassPngWriter png(png_tmp, grid.width, grid.height);
        lidar::ClassGeoTiffWriter tif(tif_tmp, grid, report.epsg);
        lidar::MaskPngWriter mask(mask_tmp, grid.width, grid.height);
        summary = lidar::merge_tile_files(paths, o.areas, [&](int row0, const Image<std::uint8_t>& classes, const lidar::Mask& s) {
          png.rows(classes), tif.rows(classes);
          if (a.footprints.empty()) return mask.rows(s);
          const lidar::Mask truth = lidar::rasterise_footprints(polygons, grid, row0, s.height());
          const lidar::Mask coverage = lidar::rasterise_coverage(polygons, grid, row0, s.height());
          const lidar::Scores band = lidar::compare_masks(s, truth, &coverage);
          tp += band.tp, fp += band.fp, fn += band.fn;
          mask.rows(s, &truth);
        });
        png.close(), tif.close(), mask.close();
      });
    });
  });
  if (!a.footprints.empty()) report.building_mask = lidar::scores_from_counts(tp, fp, fn);
  const lidar::BuiltUpRaster stats{summary.grid, {}, {}, summary.stats};
  report.raster = &stats;
  lidar::write_report(a.out, report);
  const std::string markdown = lidar::report_markdown(report);
  report.raster = nullptr;  // `stats` ends here
  return markdown;
}

void run_lidar(LidarArgs a) {
  lidar::check_epsg(a.epsg, "--epsg");  // before any output exists: a code GDAL does not know is a usage error
  lidar::BuiltUpOptions o = options_of(a);
  if (!a.sweep.empty()) sweep_values(a.sweep);  // a bad value fails before the points are read
  lidar::Report report;
  report.options = o;
  report.outputs = {"classes.png", "classes.tif", "buildings.png", "report.json", "report.md"};
  a.shown_out = a.out;
  // A single run or a merge builds its files in a private folder that replaces --out in one step at the end
  // (core/output_transaction.h): an interruption leaves the previous complete set or the new one, never a mix.
  std::optional<OutputTransaction> outputs;
  const bool tile_task = a.merge.empty() && !a.tiles.empty();
  if (tile_task) {
    prepare_output_folder(a.out);
  } else {
    outputs.emplace(a.out);
    a.out = outputs->folder();
  }

  // Synthetic settlements: written as LAS so the run reads them like any survey; their truth validates the run.
  std::optional<lidar::SyntheticSettlements> scene;
  if (a.inputs.size() == 1 && a.inputs[0].rfind("synthetic:", 0) == 0) {
    lidar::SyntheticSettlementOptions so;
    so.cell_m = a.cell_m;
    const std::vector<double> seed = numbers(a.inputs[0].substr(10), "--input synthetic:SEED");
    // A whole number a double holds exactly: -3 or 1e300 would wrap or overflow in the cast.
    if (seed.size() != 1 || !(seed[0] >= 0 && seed[0] <= 9007199254740992.0) || seed[0] != std::floor(seed[0]))
      throw Error("--input synthetic:SEED: expected a whole number 0..2^53, got '" + a.inputs[0].substr(10) + "'");
    so.seed = static_cast<std::uint64_t>(seed[0]);
    scene = lidar::synthetic_settlements(so);
    if (a.areas.empty()) o.areas = scene->areas, report.options.areas = scene->areas;
    LasHeader h;
    h.version_minor = 4, h.point_format = 6;
    h.scale[0] = h.scale[1] = h.scale[2] = 0.001;
    a.inputs = {a.out + "/synthetic.las"};
    write_las(a.inputs[0], h, scene->points);
    report.outputs.push_back("synthetic.las");
  }
  report.inputs = a.inputs;
  if (scene) report.inputs = {a.shown_out + "/synthetic.las"};  // where it will be, not the private folder

  lidar::Grid grid;
  if (!a.merge.empty()) {
    const std::string markdown = run_merge(a, o, report);
    outputs->commit(previous_lidar_run_wrote(outputs->target()));
    std::cout << markdown << "\noutputs in " << a.shown_out << "\n";
    return;
  }

  if (a.inputs.empty()) throw Error("--input: at least one LAS file (or synthetic:SEED)");
  grid = lidar::grid_of_files(a.inputs, o.cell_m);
  report.epsg = a.epsg;
  if (report.epsg == 0) {
    // A code the file states but GDAL does not know (a local or withdrawn one) leaves the outputs without a CRS,
    // as a file stating none does; said once, so it is not silent.
    report.epsg = las_epsg(LasReader(a.inputs[0]).header());
    try {
      lidar::check_epsg(report.epsg, a.inputs[0]);
    } catch (const Error& e) {
      std::fprintf(stderr, "hashfusion lidar: %s; the outputs get no CRS (give --epsg)\n", e.what());
      report.epsg = 0;
    }
  }

  if (!a.tiles.empty()) {
    const auto [nx, ny] = tile_counts(a.tiles);
    const lidar::TileLimits limits{a.max_height_m, a.max_building_m};
    const lidar::TilePlan plan = lidar::plan_tiles(grid, nx, ny, o, limits);
    if (a.tile < 0 || a.tile >= plan.count())
      throw Error("--tile: expected 0.." + std::to_string(plan.count() - 1) + " with --tiles " + a.tiles);
    const lidar::TileResult t = lidar::run_tile(a.inputs, plan, a.tile, o, limits, true);
    const std::string path = a.out + "/tile_" + std::to_string(a.tile) + ".hflt";
    lidar::write_tile(path, t);
    std::cout << "tile " << a.tile << " of " << plan.count() << " (halo " << plan.halo_cells << " cells) written to " << path << "\n";
    return;
  }

  // Footprints first: a bad footprint file should fail before the points are read.
  std::optional<lidar::Mask> truth, coverage;
  if (!a.footprints.empty()) {
    const auto polygons = lidar::read_footprints(a.footprints, a.footprint_layer, &grid);
    truth = lidar::rasterise_footprints(polygons, grid), coverage = lidar::rasterise_coverage(polygons, grid);
  } else if (scene) {
    truth = scene->footprints;
  }
  const lidar::CellRaster raster = lidar::rasterise_files(a.inputs, grid, o.classes, true, lidar::OutsideGrid::refuse);
  lidar::BuiltUp b = lidar::classify_built_up(raster, o);
  const std::optional<Image<std::uint8_t>> class_truth = scene ? std::optional(scene->classes) : std::nullopt;
  if (!a.sweep.empty()) {
    for (double t : sweep_values(a.sweep)) {
      lidar::reclassify(b, t, o.areas, o.cell_m);
      lidar::SweepRow row{t, b.profile.stats, std::nullopt};
      if (class_truth) row.validation = lidar::compare_classes(b.profile.classes, *class_truth);
      report.sweep.push_back(row);
    }
    lidar::reclassify(b, o.t_s, o.areas, o.cell_m);
  }
  if (class_truth) report.validation = lidar::compare_classes(b.profile.classes, *class_truth);
  const lidar::BuiltUpRaster result = lidar::built_up_raster(b, grid);
  const std::string markdown =
      write_outputs(a, report, result, truth ? &*truth : nullptr, coverage ? &*coverage : nullptr);
  outputs->commit(previous_lidar_run_wrote(outputs->target()));
  std::cout << markdown << "\noutputs in " << a.shown_out << "\n";
}

}  // namespace

void add_lidar_command(CLI::App& app) {
  auto args = std::make_shared<LidarArgs>();
  CLI::App* cmd = app.add_subcommand("lidar", "classify built-up areas (hamlet / village / town / city) in LiDAR point clouds");
  cmd->add_option("--input", args->inputs, "LAS 1.0-1.4 files (LAZ must be decompressed first), or synthetic:SEED");
  add_out_option(cmd, args->out, "output folder");
  cmd->add_option("--cell-m", args->cell_m, "grid resolution r in metres")->check(positive())->capture_default_str();
  auto* t = cmd->add_option("--t-m-per-m", args->t_s, "t^S: dilation radius (m) per metre of building height")
                ->check(in_range(0, kMaxTMPerM, "m per m"))
                ->capture_default_str();
  add_deprecated_alias(cmd, t, "--t", args->t_s);
  auto* areas = cmd->add_option("--areas-m2", args->areas,
                                "area thresholds a1,a2,a3 in m^2 (default 50000,1000000,5000000)");
  add_deprecated_alias(cmd, areas, "--areas", args->areas);
  cmd->add_option("--ground-margin-m", args->ground_margin_m, "ground box around each building (metres)")->capture_default_str();
  cmd->add_option("--footprints", args->footprints, "building footprints (any GDAL vector format) to validate the building mask");
  cmd->add_option("--footprint-layer", args->footprint_layer, "layer of --footprints (default: the first)");
  cmd->add_option("--epsg", args->epsg, "CRS of the outputs when the LAS files do not state it");
  auto* sweep = cmd->add_option("--sweep-t-m-per-m", args->sweep, "sensitivity analysis over t^S, e.g. 0.5,1,1.5,2,3");
  add_deprecated_alias(cmd, sweep, "--sweep-t", args->sweep);
  cmd->add_option("--tiles", args->tiles, "tiled run: NX,NY tiles over the inputs' grid (with --tile)");
  cmd->add_option("--tile", args->tile, "the tile (0..NX*NY-1) this process computes; writes OUT/tile_K.hflt");
  cmd->add_option("--merge", args->merge, "merge the tile_*.hflt files of this folder into the final outputs");
  cmd->add_option("--max-height-m", args->max_height_m, "tiled run: tallest building expected")->capture_default_str();
  cmd->add_option("--max-building-m", args->max_building_m, "tiled run: widest building expected")->capture_default_str();
  cmd->callback([args] { run_lidar(*args); });
}

}  // namespace hf::apps
