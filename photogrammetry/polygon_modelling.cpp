#include "photogrammetry/polygon_modelling.h"

#include <cmath>
#include <map>

#include "core/error.h"

namespace hf::photogrammetry {
namespace {

// The plane's normal turned towards the camera centre C (a facade seen from outside faces out).
Eigen::Vector4d facing(Eigen::Vector4d plane, const Eigen::Vector3d& C) {
  if (plane.head<3>().dot(C) + plane[3] < 0) plane = -plane;
  return plane;
}

std::vector<Eigen::Vector3d> onto_plane(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector4d& plane) {
  std::vector<Eigen::Vector3d> out;
  const Eigen::Vector3d n = plane.head<3>();
  for (const auto& p : points) out.push_back(p - (n.dot(p) + plane[3]) * n);
  return out;
}

std::vector<double> vertex_errors(const Network& network, const SketchPolygon& p,
                                  const std::vector<Eigen::Vector3d>& vertices) {
  std::vector<double> errors;
  for (size_t k = 0; k < vertices.size(); ++k) {
    double sum = 0;
    int count = 0;
    for (const SketchView& v : p.views) {
      const Shot& shot = network.shots[size_t(network.shot_index(v.shot))];
      const auto uv = shot.project(vertices[k]);
      if (!uv) continue;  // behind this view's camera: no pixel to compare
      sum += (*uv - v.points[k]).squaredNorm();
      ++count;
    }
    errors.push_back(count ? std::sqrt(sum / count) : 0.0);
  }
  return errors;
}

ModelledPolygon model_one(const Network& network, const SketchPolygon& p, const std::vector<PlaneSegment>& segments,
                          const std::map<std::string, const ModelledPolygon*>& done, const ModelOptions& o) {
  ModelledPolygon m;
  m.id = p.id;
  const SketchView& first = p.views[0];
  const int first_index = network.shot_index(first.shot);
  const Shot& first_shot = network.shots[size_t(first_index)];

  m.fits = fit_segments(first_shot, first_index, first.points, network.cloud, segments, o.fit);
  const CandidateChoice choice = choose_candidate(m.fits, o.fit);
  m.candidate = choice.best;

  std::vector<Eigen::Vector3d> triangulated;
  bool dlt_ok = p.views.size() >= 2;
  if (p.views.size() >= 2) {
    for (size_t k = 0; k < first.points.size(); ++k) {
      std::vector<DltObservation> obs;
      for (const SketchView& v : p.views)
        obs.push_back(observation(network.shots[size_t(network.shot_index(v.shot))], v.points[k]));
      m.triangulations.push_back(triangulate_dlt(obs, o.dlt));
      dlt_ok = dlt_ok && m.triangulations.back().ok();
      triangulated.push_back(m.triangulations.back().X_world);
    }
  }
  std::optional<Eigen::Vector4d> dlt_plane;
  if (dlt_ok) {
    dlt_plane = fit_plane(triangulated);
    dlt_ok = dlt_plane.has_value();
  }

  std::optional<Eigen::Vector4d> reference_plane;
  if (!p.same_plane_as.empty()) {
    const auto it = done.find(p.same_plane_as);
    if (it != done.end() && it->second->plane) reference_plane = it->second->plane;
  }
  std::optional<std::vector<Eigen::Vector3d>> on_reference, on_segment;
  if (reference_plane) on_reference = back_project_onto_plane(first_shot, first.points, *reference_plane);
  if (choice.best) on_segment = back_project_onto_plane(first_shot, first.points, segments[size_t(choice.best->segment)].plane);

  GuidanceInputs in;
  in.reference_plane = on_reference.has_value();
  in.shots = int(p.views.size());
  in.dlt_ok = dlt_ok;
  in.cloud_candidate = on_segment.has_value();
  in.cloud_ambiguous = choice.ambiguous;
  m.decision = decide_guidance(in);
  if (reference_plane && !on_reference)
    m.decision.reason += " (the outline's rays miss the plane of " + quote_for_message(p.same_plane_as) + ")";

  switch (m.decision.method) {
    case Placement::polygon_plane:
      m.vertices = *on_reference;
      m.plane = *reference_plane;
      break;
    case Placement::cloud_plane:
      m.vertices = *on_segment;
      m.plane = segments[size_t(choice.best->segment)].plane;
      break;
    case Placement::dlt: {
      Eigen::Vector4d plane = *dlt_plane;
      if (choice.best && o.adjust_to_segment_deg > 0 &&
          plane_angle_deg(plane, segments[size_t(choice.best->segment)].plane) <= o.adjust_to_segment_deg) {
        plane = segments[size_t(choice.best->segment)].plane;
        m.adjusted_to_segment = true;
        m.decision.reason += ", adjusted to the cloud segment's plane";
      }
      m.vertices = onto_plane(triangulated, plane);
      m.plane = plane;
      break;
    }
    case Placement::none: break;
  }
  if (m.plane) m.plane = facing(*m.plane, first_shot.C_world);
  m.reprojection_error_px = vertex_errors(network, p, m.vertices);
  return m;
}

}  // namespace

Model model_polygons(const Network& network, const Sketch& sketch, std::vector<PlaneSegment> segments,
                     const ModelOptions& options) {
  Model model;
  model.segments = std::move(segments);
  model.polygons.reserve(sketch.polygons.size());  // `done` points into it
  std::map<std::string, const ModelledPolygon*> done;
  for (const SketchPolygon& p : sketch.polygons) {
    model.polygons.push_back(model_one(network, p, model.segments, done, options));
    done[p.id] = &model.polygons.back();
  }
  return model;
}

Model model_polygons(const Network& network, const Sketch& sketch, const ModelOptions& options) {
  return model_polygons(network, sketch, segment_planes_ransac(network.cloud.positions, options.ransac), options);
}

}  // namespace hf::photogrammetry
