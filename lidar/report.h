// The run's tables in Markdown and JSON (written atomically). report.json keeps stable keys for scripts:
//   parameters {inputs, cell_m, t_s, areas_m2 [a1, a2, a3], ground_margin_m, epsg, tiles}
//   grid {west, north, width, height, cell_m}
//   classes {hamlet|village|town|city: {cells, components, settlements, area_m2}}   components = buildings C_i
//   building_mask {completeness, correctness, f1, tp, fp, fn}        when footprints are given
//   validation {hamlet|...: {completeness, correctness, f1} | null, mean_f1}   when a class truth is known
//   sensitivity [{t_s, classes {NAME: cells}, mean_f1?}]              when a sweep of t^S ran
//   outputs [file names]                                              what the run wrote into its folder
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lidar/tiling.h"
#include "lidar/validation.h"

namespace hf::lidar {

struct SweepRow {
  double t_s = 0;
  std::array<ClassStatistics, kBuiltUpClasses> stats;
  std::optional<ClassValidation> validation;
};

struct Report {
  std::vector<std::string> inputs;
  BuiltUpOptions options;
  int epsg = 0;
  std::string tiles;  // "NX x NY" for a merged run, empty for a single one
  const BuiltUpRaster* raster = nullptr;
  std::optional<Scores> building_mask;
  std::optional<ClassValidation> validation;
  std::vector<SweepRow> sweep;
  std::vector<std::string> outputs;  // the files the run wrote into its folder (report.json "outputs")
};

nlohmann::json report_json(const Report& r);
std::string report_markdown(const Report& r);
// Writes DIR/report.json and DIR/report.md.
void write_report(const std::string& dir, const Report& r);

}  // namespace hf::lidar
