// Head-model feature recognition (head/, Kubásková): the per-vertex curvature evaluations and the whole method
// (areas, features, control points) on numpy vertices / faces, in the mesh's own frame and units.
#include <pybind11/stl.h>

#include "head/discrete_curvature.h"
#include "head/head_features.h"
#include "head/mls_curvature.h"
#include "mesh/topology.h"
#include "python/src/bindings.h"
#include "python/src/convert.h"

namespace hf::python {
namespace {

// Through hashfusion.Mesh's constructor: the same checks (shapes, dtypes, face indices) and messages.
TriangleMesh mesh_from_arrays(const py::object& vertices, const py::object& faces) {
  return py::module_::import("hashfusion._hashfusion").attr("Mesh")(vertices, faces).cast<TriangleMesh>();
}

template <class T>
py::array_t<T> vector_to_array(const std::vector<T>& values) {
  return py::array_t<T>(py::ssize_t(values.size()), values.data());
}

// {mean, gaussian, k_max, k_min, valid} as (N,) arrays; 1 / mesh unit (gaussian 1 / unit^2), 0 where invalid.
py::dict curvatures_to_python(const head::VertexCurvatures& c) {
  py::dict d;
  d["mean"] = vector_to_array(c.mean);
  d["gaussian"] = vector_to_array(c.gaussian);
  d["k_max"] = vector_to_array(c.k_max);
  d["k_min"] = vector_to_array(c.k_min);
  d["valid"] = vector_to_array(c.valid).attr("astype")("bool");
  return d;
}

py::dict curvature(const py::object& vertices, const py::object& faces, const std::string& method) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, faces);
  const head::Evaluation evaluation = head::parse_evaluation(method);
  if (evaluation == head::Evaluation::laplace)
    throw ValueError("curvature: method must be discrete or mls (laplace is not a curvature)");
  head::VertexCurvatures c;
  {
    py::gil_scoped_release release;
    const MeshTopology topology = build_topology(mesh);
    c = evaluation == head::Evaluation::mls ? head::mls_curvature(mesh, topology)
                                            : head::discrete_curvature(mesh, topology);
  }
  return curvatures_to_python(c);
}

py::dict head_features(const py::object& vertices, const py::object& faces, const std::string& method,
                       const std::string& quantity, bool automatic, const py::object& threshold,
                       const std::string& morphology) {
  const TriangleMesh mesh = mesh_from_arrays(vertices, faces);
  head::HeadFeatureOptions o;
  o.evaluation = head::parse_evaluation(method);
  o.quantity = head::parse_quantity(quantity);
  o.automatic = automatic;
  o.morphology = head::parse_morphology(morphology);
  if (!threshold.is_none()) {
    o.has_threshold = true;
    o.threshold = head::parse_threshold(py::str(threshold).cast<std::string>());
  }
  head::HeadFeatureResult r;
  {
    py::gil_scoped_release release;
    r = head::detect_head_features(mesh, o);
  }
  py::dict d;
  d["discrete"] = curvatures_to_python(r.discrete);
  d["mls"] = curvatures_to_python(r.mls);
  d["laplace"] = vector_to_array(r.laplace.magnitude);
  d["evaluation_percent"] = vector_to_array(r.evaluation_percent);
  d["threshold"] = py::make_tuple(r.threshold_a, r.threshold_b);
  d["features"] = vector_to_array(r.features).attr("astype")("bool");
  std::vector<std::uint8_t> area(r.areas.label.size());
  for (size_t i = 0; i < area.size(); ++i) area[i] = static_cast<std::uint8_t>(r.areas.label[i]);
  d["area"] = vector_to_array(area);
  d["nose_tip_vertex"] = r.frame.nose_tip_vertex;
  py::list points;
  for (const head::ControlPoint& p : r.control_points) {
    py::dict cp;
    cp["name"] = p.name;
    cp["vertex"] = p.vertex;
    cp["position"] = vector_to_array(std::vector<float>{p.position.x(), p.position.y(), p.position.z()});
    points.append(cp);
  }
  d["control_points"] = points;
  d["warnings"] = r.warnings;
  return d;
}

}  // namespace

void bind_head(py::module_& m) {
  m.def("curvature", &curvature, py::arg("vertices"), py::arg("faces"), py::arg("method") = "discrete",
        "per-vertex curvature of a triangle mesh (method discrete: Meyer et al.; mls: the modified MLS fit) -> "
        "dict of (N,) arrays mean, gaussian, k_max, k_min (1 / mesh unit), valid (bool)");
  m.def("head_features", &head_features, py::arg("vertices"), py::arg("faces"), py::arg("method") = "discrete",
        py::arg("quantity") = "mean", py::arg("automatic") = false, py::arg("threshold") = py::none(),
        py::arg("morphology") = "",
        "Kubásková's head-feature recognition, as `hashfusion head-features` (threshold 'a,b' in eq. 10's %, "
        "default: the evaluation's average .. 100; morphology e.g. 'open:5,dilate:10') -> dict: discrete / mls "
        "curvatures, laplace, evaluation_percent, threshold, features (bool), area (uint8 per vertex), "
        "nose_tip_vertex, control_points [{name, vertex, position}], warnings");
}

}  // namespace hf::python
