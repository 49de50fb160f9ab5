#include "head/feature_outputs.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "head/render.h"
#include "io/ply.h"

namespace hf::head {
namespace {

const Rgb8 kAreaColors[kAreaCount] = {{200, 200, 200}, {90, 160, 255}, {60, 110, 220}, {80, 200, 120},
                                      {255, 150, 170}, {240, 200, 80},  {210, 160, 40}};
const Rgb8 kFeatureColor{220, 30, 30};
const Rgb8 kNotEvaluated{128, 128, 128};

// features.png's legend: each important area's colour, the features' and the control points' markers.
std::vector<LegendEntry> feature_legend() {
  std::vector<LegendEntry> out;
  for (int k = 0; k < kAreaCount; ++k)
    out.push_back({k == 0 ? std::string("outside the areas") : std::string(area_name(static_cast<Area>(k))),
                   kAreaColors[k]});
  out.push_back({"feature", kFeatureColor});
  out.push_back({"control point (marker)", Rgb8{0, 0, 0}});
  return out;
}

Rgb8 diverging_bar(double v, double, double hi) { return diverging_color(v, hi); }

struct Channel {
  const char* name;
  const std::vector<float>* values;
  const VertexMask* valid;
};

std::vector<Channel> channels(const HeadFeatureResult& r, const HeadFeatureOptions& o) {
  const VertexCurvatures& c = o.evaluation == Evaluation::mls ? r.mls : r.discrete;
  return {{"mean_curvature", &c.mean, &c.valid},
          {"gaussian_curvature", &c.gaussian, &c.valid},
          {"k1", &c.k_max, &c.valid},
          {"k2", &c.k_min, &c.valid},
          {"laplace", &r.laplace.magnitude, &r.laplace.valid}};
}

template <class T>
void put(std::string& out, T v) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  out.append(b, sizeof(T));  // little endian on every platform hashfusion builds for (x86-64, arm64)
}

void write_evaluations_ply(const std::string& path, const TriangleMesh& mesh, const HeadFeatureResult& r,
                           const HeadFeatureOptions& o) {
  const std::vector<Channel> ch = channels(r, o);
  std::ostringstream header;
  header << "ply\nformat binary_little_endian 1.0\ncomment written by hashfusion head-features\n"
         << "comment curvatures: " << (o.evaluation == Evaluation::mls ? "mls" : "discrete")
         << " (1/unit, gaussian 1/unit^2); laplace: |delta| of eq. 9; invalid vertices 0\n"
         << "element vertex " << mesh.vertices.size() << "\nproperty float x\nproperty float y\nproperty float z\n";
  for (const Channel& c : ch) header << "property float " << c.name << "\n";
  header << "property uchar area\nproperty uchar feature\nelement face " << mesh.triangles.size()
         << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body = header.str();
  body.reserve(body.size() + mesh.vertices.size() * 34 + mesh.triangles.size() * 13);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    for (int k = 0; k < 3; ++k) put<float>(body, mesh.vertices[i][k]);
    for (const Channel& c : ch) put<float>(body, (*c.valid)[i] ? (*c.values)[i] : 0.0f);
    put<std::uint8_t>(body, static_cast<std::uint8_t>(r.areas.label[i]));
    put<std::uint8_t>(body, r.features[i] ? 1 : 0);
  }
  for (const Eigen::Vector3i& t : mesh.triangles) {
    put<std::uint8_t>(body, 3);
    for (int k = 0; k < 3; ++k) put<std::int32_t>(body, t[k]);
  }
  write_file_atomically(path, [&](std::ostream& os) { os << body; }, true);
}

// The diverging colours of `w` at its valid vertices, scaled to the 95th percentile of |w| (returned in *scale, so
// the legend can label the bar); grey where not valid.
std::vector<Rgb8> color_map(const std::vector<float>& w, const VertexMask& valid, double* scale_out = nullptr) {
  std::vector<float> mags;
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i]) mags.push_back(std::abs(w[i]));
  double scale = 0;
  if (!mags.empty()) {
    const size_t k = std::min(mags.size() - 1, static_cast<size_t>(0.95 * mags.size()));
    std::nth_element(mags.begin(), mags.begin() + static_cast<long>(k), mags.end());
    scale = mags[k];
  }
  std::vector<Rgb8> out(w.size(), kNotEvaluated);
  for (size_t i = 0; i < w.size(); ++i)
    if (valid[i]) out[i] = diverging_color(w[i], scale);
  if (scale_out) *scale_out = scale;
  return out;
}

std::vector<Rgb8> feature_colors(const HeadFeatureResult& r) {
  std::vector<Rgb8> out(r.areas.label.size());
  for (size_t i = 0; i < out.size(); ++i)
    out[i] = r.features[i] ? kFeatureColor : kAreaColors[static_cast<int>(r.areas.label[i])];
  return out;
}

// Front (looking at the face), the subject's right and left profiles, as rotations input -> view.
std::vector<Eigen::Matrix3f> views(const HeadFrame& f) {
  const Eigen::Matrix3f R = f.R_head_input.cast<float>();
  Eigen::Matrix3f front, right, left;
  front << R.row(0), R.row(2), R.row(1);
  right << -R.row(1), R.row(2), R.row(0);  // viewer at +x (the subject's right), nose pointing left in the image
  left << R.row(1), R.row(2), -R.row(0);
  return {front, right, left};
}

nlohmann::json vec(const Eigen::Vector3f& v) { return {v.x(), v.y(), v.z()}; }

nlohmann::json control_points_json(const HeadFeatureResult& r) {
  nlohmann::json points = nlohmann::json::array();
  std::vector<std::string> found;
  for (const ControlPoint& c : r.control_points) {
    points.push_back({{"name", c.name}, {"vertex", c.vertex}, {"position", vec(c.position)}});
    found.push_back(c.name);
  }
  nlohmann::json missing = nlohmann::json::array();
  for (const std::string& n : control_point_names())
    if (std::find(found.begin(), found.end(), n) == found.end()) missing.push_back(n);
  // Why an area's points are absent (an ear under hair), from the area detection; empty where not known.
  nlohmann::json absent = nlohmann::json::object();
  for (int a = 1; a < kAreaCount; ++a)
    if (r.areas.counts[a] == 0 && !r.areas.note[a].empty()) absent[area_name(static_cast<Area>(a))] = r.areas.note[a];
  return {{"frame", "input mesh"}, {"control_points", points}, {"missing", missing}, {"absent_areas", absent}};
}

nlohmann::json report_json(const TriangleMesh& mesh, const HeadFeatureResult& r, const HeadFeatureOptions& o,
                           const OutputInfo& info) {
  nlohmann::json j;
  j["input"] = info.input_path;
  j["mesh"] = {{"vertices", mesh.vertices.size()},
               {"triangles", mesh.triangles.size()},
               {"boundary_edges", r.topology.boundary_edge_count},
               {"non_manifold_edges", r.topology.non_manifold_edge_count},
               {"isolated_vertices", r.topology.isolated_vertex_count},
               {"degenerate_triangles", r.topology.degenerate_triangles.size()},
               {"mean_edge_length", r.frame.mean_edge_length}};
  nlohmann::json R = nlohmann::json::array();
  for (int i = 0; i < 3; ++i) R.push_back({r.frame.R_head_input(i, 0), r.frame.R_head_input(i, 1), r.frame.R_head_input(i, 2)});
  j["head_frame"] = {{"convention", "p_head = scale * R_head_input * (p_input - origin_input); x subject's right, "
                                    "y towards the nose, z up"},
                     {"R_head_input", R},
                     {"origin_input", {r.frame.origin_input.x(), r.frame.origin_input.y(), r.frame.origin_input.z()}},
                     {"scale", r.frame.scale},
                     {"nose_tip_vertex", r.frame.nose_tip_vertex},
                     {"symmetry_rms_edges", r.frame.symmetry_rms_edges},
                     {"cap_scale", r.frame.cap_scale},
                     {"recession_above_below_edges", {r.frame.recession_above, r.frame.recession_below}},
                     {"width_above_below_edges", {r.frame.width_above, r.frame.width_below}}};
  nlohmann::json areas;
  for (int a = 0; a < kAreaCount; ++a)
    areas[area_name(static_cast<Area>(a))] = {{"vertices", r.areas.counts[a]},
                                              {"threshold_percent", r.area_features.threshold_percent[a]},
                                              {"note", r.areas.note[a]}};
  long features = std::count(r.features.begin(), r.features.end(), 1);
  j["important_areas"] = {{"k", r.areas.k},
                          {"mean_curvature_threshold", r.areas.threshold},
                          {"separation_method", o.areas.separation_method},
                          {"z_eyes_nose_edges", r.areas.z_eyes_nose},
                          {"z_nose_lips_edges", r.areas.z_nose_lips},
                          {"z_nose_root_edges", r.areas.z_root},
                          {"areas", areas}};
  // The physical scales (head_features.h; all 0: the paper's scales).
  j["physical_scale"] = {{"evaluation_sigma_rho", o.evaluation_sigma_rho},
                         {"mls_h_rho", o.mls_h_rho},
                         {"mls_truncate_percent", o.mls_truncate_percent},
                         {"area_k_rho", o.areas.k_rho},
                         {"eyes_nose_root_fraction", o.areas.root_fraction}};
  nlohmann::json morph = nlohmann::json::array();
  for (const MorphologyStep& s : o.morphology) morph.push_back(std::string(morphology_op_name(s.op)) + ":" + std::to_string(s.k));
  j["features"] = {{"mode", o.automatic ? "automatic (section 4.5)" : "manual"},
                   {"method", evaluation_name(o.evaluation)},
                   {"quantity", o.evaluation == Evaluation::laplace ? "magnitude" : quantity_name(o.quantity)},
                   {"threshold_percent", {r.threshold_a, r.threshold_b}},
                   {"truncate_percent", o.truncate_percent},
                   {"morphology", morph},
                   {"vertices", features}};
  j["valid_vertices"] = {{"discrete", r.discrete.valid_count}, {"mls", r.mls.valid_count}, {"laplace", r.laplace.valid_count}};
  j["control_points"] = control_points_json(r);
  j["warnings"] = r.warnings;
  j["stage_ms"] = r.stage_ms;
  return j;
}

std::string report_markdown(const nlohmann::json& j) {
  std::ostringstream md;
  md << "# head-features: " << j["input"].get<std::string>() << "\n\n";
  md << "| mesh | value |\n|---|---|\n";
  for (auto& [k, v] : j["mesh"].items()) md << "| " << k << " | " << v.dump() << " |\n";
  md << "\n## Head frame\n\n" << j["head_frame"]["convention"].get<std::string>() << "\n\n";
  md << "- nose tip vertex " << j["head_frame"]["nose_tip_vertex"].dump() << ", symmetry residual "
     << j["head_frame"]["symmetry_rms_edges"].dump() << " edge lengths\n- R_head_input "
     << j["head_frame"]["R_head_input"].dump() << "\n\n## Important areas (k = " << j["important_areas"]["k"].dump()
     << ", separation method " << j["important_areas"]["separation_method"].dump() << ")\n\n"
     << "| area | vertices | area threshold (%) |\n|---|---|---|\n";
  for (auto& [k, v] : j["important_areas"]["areas"].items())
    md << "| " << k << " | " << v["vertices"].dump() << " | " << v["threshold_percent"].dump() << " |\n";
  md << "\n## Features\n\n" << j["features"]["mode"].get<std::string>() << ", method "
     << j["features"]["method"].get<std::string>() << " (" << j["features"]["quantity"].get<std::string>()
     << "), threshold " << j["features"]["threshold_percent"].dump() << " %, morphology "
     << j["features"]["morphology"].dump() << ": " << j["features"]["vertices"].dump() << " vertices\n\n";
  md << "## Control points\n\n" << j["control_points"]["control_points"].size() << " found, missing: "
     << j["control_points"]["missing"].dump() << "\n\n| name | vertex | position |\n|---|---|---|\n";
  for (auto& c : j["control_points"]["control_points"])
    md << "| " << c["name"].get<std::string>() << " | " << c["vertex"].dump() << " | " << c["position"].dump() << " |\n";
  md << "\n## Warnings\n\n";
  if (j["warnings"].empty()) md << "none\n";
  for (auto& w : j["warnings"]) md << "- " << w.get<std::string>() << "\n";
  md << "\n## Stage timings (ms)\n\n| stage | ms |\n|---|---|\n";
  for (auto& [k, v] : j["stage_ms"].items()) md << "| " << k << " | " << v.dump() << " |\n";
  return md.str();
}

}  // namespace

Rgb8 diverging_color(double value, double scale) {
  const double t = scale > 0 ? std::clamp(value / scale, -1.0, 1.0) : 0.0;
  auto c = [](double x) { return static_cast<std::uint8_t>(std::lround(std::clamp(x, 0.0, 255.0))); };
  if (t >= 0) return {255, c(255 * (1 - t)), c(255 * (1 - t))};
  return {c(255 * (1 + t)), c(255 * (1 + t)), 255};
}

void write_head_feature_outputs(const std::string& dir, const TriangleMesh& mesh, const HeadFeatureResult& r,
                                const HeadFeatureOptions& o, const OutputInfo& info) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!std::filesystem::is_directory(dir)) throw Error(dir + ": cannot create the output folder");
  const std::string base = dir + "/";
  write_evaluations_ply(base + "evaluations.ply", mesh, r, o);
  TriangleMesh colored = mesh;
  colored.normals.clear();
  for (const Channel& c : channels(r, o)) {
    colored.colors = color_map(*c.values, *c.valid);
    write_ply(base + c.name + ".ply", colored);
  }
  colored.colors = feature_colors(r);
  write_ply(base + "features.ply", colored);

  std::vector<RenderMarker> markers;
  for (const ControlPoint& c : r.control_points) markers.push_back({c.position, {0, 0, 0}, ""});
  const RenderOptions ro{.width_px = 600, .height_px = 600};
  write_png(base + "features.png",
            with_swatch_legend(render_views(mesh, views(r.frame), colored.colors, markers, ro), feature_legend()));
  const VertexMask* valid = nullptr;
  raw_evaluation(r, o, &valid);
  double scale = 0.0;
  const std::vector<Rgb8> evaluation_colors = color_map(r.evaluation_percent, *valid, &scale);
  write_png(base + "evaluation.png",
            with_color_bar(render_views(mesh, {views(r.frame)[0], views(r.frame)[1]}, evaluation_colors, {}, ro),
                           -scale, scale, diverging_bar,
                           "evaluation after eq. 10 (negative blue, positive red), clipped at the 95th percentile "
                           "of |value|", "%", {{"not evaluated", kNotEvaluated}}));

  const nlohmann::json cp = control_points_json(r);
  write_file_atomically(base + "control_points.json", [&](std::ostream& os) { os << cp.dump(2) << "\n"; });
  const nlohmann::json report = report_json(mesh, r, o, info);
  write_file_atomically(base + "report.json", [&](std::ostream& os) { os << report.dump(2) << "\n"; });
  write_file_atomically(base + "report.md", [&](std::ostream& os) { os << report_markdown(report); });
}

}  // namespace hf::head
