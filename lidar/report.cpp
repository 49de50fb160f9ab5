#include "lidar/report.h"

#include <cstdio>
#include <ostream>
#include <sstream>

#include "core/atomic_file.h"

namespace hf::lidar {
namespace {

const char* name_of(int k) { return class_name(static_cast<BuiltUpClass>(k + 1)); }

nlohmann::json scores_json(const Scores& s) {
  return {{"completeness", s.completeness}, {"correctness", s.correctness}, {"f1", s.f1}, {"tp", s.tp}, {"fp", s.fp}, {"fn", s.fn}};
}

std::string pct(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", 100.0 * v);
  return b;
}

}  // namespace

nlohmann::json report_json(const Report& r) {
  nlohmann::json j;
  const BuiltUpOptions& o = r.options;
  j["parameters"] = {{"inputs", r.inputs},
                     {"cell_m", o.cell_m},
                     {"t_s", o.t_s},
                     {"areas_m2", {o.areas.a1, o.areas.a2, o.areas.a3}},
                     {"ground_margin_m", o.heights.ground_margin_m},
                     {"epsg", r.epsg},
                     {"tiles", r.tiles.empty() ? "1 x 1" : r.tiles}};
  if (!r.outputs.empty()) j["outputs"] = r.outputs;
  const Grid& g = r.raster->grid;
  j["grid"] = {{"west", g.west()}, {"north", g.north()}, {"width", g.width}, {"height", g.height}, {"cell_m", g.cell_m}};
  for (int k = 0; k < kBuiltUpClasses; ++k) {
    const ClassStatistics& s = r.raster->stats[k];
    j["classes"][name_of(k)] = {{"cells", s.cells}, {"components", s.components}, {"settlements", s.settlements},
                                {"area_m2", double(s.cells) * g.cell_area_m2()}};
  }
  if (r.building_mask) j["building_mask"] = scores_json(*r.building_mask);
  if (r.validation) {
    for (int k = 0; k < kBuiltUpClasses; ++k) {
      const Scores& s = r.validation->per_class[k];
      j["validation"][name_of(k)] = s.contained ? scores_json(s) : nlohmann::json(nullptr);
    }
    j["validation"]["mean_f1"] = r.validation->mean_f1;
  }
  for (const SweepRow& row : r.sweep) {
    nlohmann::json e = {{"t_s", row.t_s}};
    for (int k = 0; k < kBuiltUpClasses; ++k) e["classes"][name_of(k)] = row.stats[k].cells;
    if (row.validation) e["mean_f1"] = row.validation->mean_f1;
    j["sensitivity"].push_back(e);
  }
  return j;
}

std::string report_markdown(const Report& r) {
  std::ostringstream md;
  const BuiltUpOptions& o = r.options;
  const Grid& g = r.raster->grid;
  md << "# Built-up areas (Cvirn, second-generation connectivity)\n\n";
  md << "Inputs: ";
  for (size_t i = 0; i < r.inputs.size(); ++i) md << (i ? ", " : "") << "`" << r.inputs[i] << "`";
  md << "\n\nGrid: " << g.width << " x " << g.height << " cells of " << g.cell_m << " m, west " << g.west() << ", north "
     << g.north() << (r.epsg > 0 ? ", EPSG:" + std::to_string(r.epsg) : std::string()) << (r.tiles.empty() ? "" : ", tiles " + r.tiles)
     << ". t^S = " << o.t_s << ", a1 / a2 / a3 = " << o.areas.a1 << " / " << o.areas.a2 << " / " << o.areas.a3
     << " m^2, ground margin " << o.heights.ground_margin_m << " m.\n\n";
  md << "| class | cells | area m^2 | buildings | settlements |\n|---|---|---|---|---|\n";
  for (int k = 0; k < kBuiltUpClasses; ++k) {
    const ClassStatistics& s = r.raster->stats[k];
    md << "| " << name_of(k) << " | " << s.cells << " | " << double(s.cells) * g.cell_area_m2() << " | " << s.components << " | "
       << s.settlements << " |\n";
  }
  if (r.building_mask) {
    const Scores& s = *r.building_mask;
    md << "\n## Building mask S against the footprints (cells inside the footprints' extent)\n\n"
       << "| completeness % | correctness % | F1 % | TP | FP | FN |\n|---|---|---|---|---|---|\n"
       << "| " << pct(s.completeness) << " | " << pct(s.correctness) << " | " << pct(s.f1) << " | " << s.tp << " | " << s.fp << " | "
       << s.fn << " |\n";
  }
  if (r.validation) {
    md << "\n## Validation per class (eqs. 7-9)\n\n| metric | hamlet | village | town | city |\n|---|---|---|---|---|\n";
    const char* metrics[] = {"comp", "corr", "F1"};
    for (int m = 0; m < 3; ++m) {
      md << "| " << metrics[m];
      for (int k = 0; k < kBuiltUpClasses; ++k) {
        const Scores& s = r.validation->per_class[k];
        md << " | " << (!s.contained ? "not contained" : pct(m == 0 ? s.completeness : m == 1 ? s.correctness : s.f1));
      }
      md << " |\n";
    }
    md << "\nMean F1 over the contained classes: " << pct(r.validation->mean_f1) << " %\n";
  }
  if (!r.sweep.empty()) {
    md << "\n## Sensitivity to t^S (Table 2's form)\n\n| t^S | hamlet cells | village cells | town cells | city cells | mean F1 % |\n"
       << "|---|---|---|---|---|---|\n";
    for (const SweepRow& row : r.sweep) {
      md << "| " << row.t_s;
      for (int k = 0; k < kBuiltUpClasses; ++k) md << " | " << row.stats[k].cells;
      md << " | " << (row.validation ? pct(row.validation->mean_f1) : "-") << " |\n";
    }
  }
  return md.str();
}

void write_report(const std::string& dir, const Report& r) {
  const std::string json = report_json(r).dump(2) + "\n", md = report_markdown(r);
  write_file_atomically(dir + "/report.json", [&](std::ostream& os) { os << json; });
  write_file_atomically(dir + "/report.md", [&](std::ostream& os) { os << md; });
}

}  // namespace hf::lidar
