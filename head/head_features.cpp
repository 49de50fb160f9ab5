#include "head/head_features.h"

#include <chrono>

#include "core/error.h"
#include "head/discrete_curvature.h"

namespace hf::head {
namespace {

class StageTimer {
 public:
  StageTimer(std::map<std::string, double>& out, std::string name)
      : out_(out), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}
  ~StageTimer() {
    out_[name_] = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  std::map<std::string, double>& out_;
  std::string name_;
  std::chrono::steady_clock::time_point start_;
};

void check_topology(const TriangleMesh& mesh, HeadFeatureResult& r) {
  const MeshTopology& t = r.topology;
  if (mesh.triangles.empty()) throw Error("the mesh has no triangles");
  if (t.boundary_edge_count > 0)
    r.warnings.push_back(std::to_string(t.boundary_edge_count) + " boundary edges: open mesh, border vertices skipped");
  if (t.non_manifold_edge_count > 0)
    r.warnings.push_back(std::to_string(t.non_manifold_edge_count) +
                         " non-manifold edges (more than two triangles): their vertices skipped");
  if (t.isolated_vertex_count > 0)
    r.warnings.push_back(std::to_string(t.isolated_vertex_count) + " isolated vertices (in no triangle) skipped");
  if (!t.degenerate_triangles.empty())
    r.warnings.push_back(std::to_string(t.degenerate_triangles.size()) +
                         " degenerate triangles (a repeated index) left out");
}

const std::vector<float>& curvature_quantity(const VertexCurvatures& c, Quantity q) {
  switch (q) {
    case Quantity::mean: return c.mean;
    case Quantity::gaussian: return c.gaussian;
    case Quantity::k_max: return c.k_max;
    case Quantity::k_min: return c.k_min;
  }
  return c.mean;
}

}  // namespace

const std::vector<float>& raw_evaluation(const HeadFeatureResult& r, const HeadFeatureOptions& options,
                                         const VertexMask** valid) {
  switch (options.evaluation) {
    case Evaluation::discrete: *valid = &r.discrete.valid; return curvature_quantity(r.discrete, options.quantity);
    case Evaluation::mls: *valid = &r.mls.valid; return curvature_quantity(r.mls, options.quantity);
    case Evaluation::laplace: *valid = &r.laplace.valid; return r.laplace.magnitude;
  }
  *valid = &r.discrete.valid;
  return r.discrete.mean;
}

void use_physical_scale(HeadFeatureOptions& options) {
  options.evaluation_sigma_rho = 0.05;
  options.mls_h_rho = 0.5;
  options.areas.root_fraction = 0.3;
  options.mls_truncate_percent = 5.0;
}

HeadFeatureResult detect_head_features(const TriangleMesh& mesh, const HeadFeatureOptions& options) {
  HeadFeatureResult r;
  {
    StageTimer t(r.stage_ms, "topology");
    r.topology = build_topology(mesh);
  }
  check_topology(mesh, r);
  {
    StageTimer t(r.stage_ms, "discrete_curvature");
    r.discrete = discrete_curvature(mesh, r.topology);
  }
  if (r.discrete.valid_count == 0) throw Error("the mesh has no interior vertex (every vertex is on a border)");
  {
    StageTimer t(r.stage_ms, "laplace_beltrami");
    r.laplace = laplace_beltrami(mesh, r.topology);
  }
  {
    StageTimer t(r.stage_ms, "head_frame");
    r.frame = find_head_frame(mesh, r.topology, options.frame);
  }
  const double rho = r.frame.cap_scale;
  if (options.evaluation_sigma_rho > 0) {
    StageTimer t(r.stage_ms, "physical_scale");
    smooth_at_scale(mesh, r.topology, options.evaluation_sigma_rho * rho, r.discrete);
    smooth_at_scale(mesh, r.topology, options.evaluation_sigma_rho * rho, r.laplace.valid, {&r.laplace.magnitude});
  }
  {
    StageTimer t(r.stage_ms, "important_areas");
    r.areas = find_important_areas(mesh, r.topology, r.discrete, r.frame, options.areas);
  }
  {
    StageTimer t(r.stage_ms, "mls_curvature");
    VertexMask only;
    if (options.evaluation != Evaluation::mls) {
      only.assign(r.topology.vertex_count, 0);
      for (int i = 0; i < r.topology.vertex_count; ++i) {
        const Area a = r.areas.label[i];
        only[i] = a == Area::eye_left || a == Area::eye_right || a == Area::ear_left || a == Area::ear_right;
      }
    }
    MlsOptions mls = options.mls;
    if (options.mls_h_rho > 0) mls.h = options.mls_h_rho * rho;
    r.mls = mls_curvature(mesh, r.topology, mls, only);
    if (options.evaluation_sigma_rho > 0) smooth_at_scale(mesh, r.topology, options.evaluation_sigma_rho * rho, r.mls);
  }
  {
    StageTimer t(r.stage_ms, "features");
    const VertexMask* valid = nullptr;
    std::vector<float> w = raw_evaluation(r, options, &valid);
    truncate_top_percent(w, *valid, options.truncate_percent);
    r.evaluation_percent = normalise_percent(w, *valid);
    r.threshold_a = options.has_threshold ? options.threshold.a
                                          : static_cast<float>(masked_mean(r.evaluation_percent, *valid));
    r.threshold_b = options.has_threshold ? options.threshold.b : 100.0f;
    r.area_features = detect_area_features(r.areas, r.discrete, r.mls, options.mls_truncate_percent);
    if (options.automatic) {
      r.features = r.area_features.features;
    } else {
      r.features = threshold(r.evaluation_percent, *valid, r.threshold_a, r.threshold_b);
      r.features = apply_morphology(r.topology, r.features, options.morphology);
    }
  }
  {
    StageTimer t(r.stage_ms, "control_points");
    // Control points always come from the area-specific features: the manual features need not cover an area.
    r.control_points = find_control_points(mesh, r.topology, r.frame, r.areas, r.area_features.features);
  }
  for (int a = 1; a < kAreaCount; ++a) {
    const std::string name = area_name(static_cast<Area>(a));
    if (r.areas.counts[a] == 0)
      r.warnings.push_back("area " + name + " not found" + (r.areas.note[a].empty() ? "" : ": " + r.areas.note[a]));
    else if (!r.areas.note[a].empty() && (a != static_cast<int>(Area::eye_left)))  // the eyes share one note
      r.warnings.push_back("area " + name + ": " + r.areas.note[a]);
  }
  return r;
}

}  // namespace hf::head
