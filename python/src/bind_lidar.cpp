// LiDAR built-up-area classification (lidar/, Cvirn): on LAS files or on point arrays, and the synthetic
// settlements with an exact answer. Rasters come out as (H, W) arrays, row 0 the northern edge.
#include <pybind11/stl.h>

#include <cstring>

#include "lidar/built_up_areas.h"
#include "lidar/synthetic_settlements.h"
#include "python/src/bindings.h"
#include "python/src/convert.h"

namespace hf::python {
namespace {

template <class T>
py::array_t<T> image_to_array(const Image<T>& image) {
  py::array_t<T> a({py::ssize_t(image.height()), py::ssize_t(image.width())});
  if (image.size() > 0) std::memcpy(a.mutable_data(), image.data(), image.size() * sizeof(T));
  return a;
}

py::dict grid_to_python(const lidar::Grid& g) {
  py::dict d;
  d["cell_m"] = g.cell_m;
  d["west"] = g.west();
  d["north"] = g.north();
  d["width"] = g.width;
  d["height"] = g.height;
  return d;
}

// (N, 3) x y z metres and (N,) LAS classification codes -> points.
std::vector<LasPoint> points_from_arrays(const py::handle& xyz, const py::handle& classification) {
  auto p = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(xyz);
  auto c = py::array_t<std::uint8_t, py::array::c_style | py::array::forcecast>::ensure(classification);
  if (!p || p.ndim() != 2 || p.shape(1) != 3) throw ValueError("lidar_classify: points must be an (N, 3) array");
  if (!c || c.ndim() != 1 || c.shape(0) != p.shape(0))
    throw ValueError("lidar_classify: classification must be an (N,) array of LAS class codes");
  std::vector<LasPoint> points(size_t(p.shape(0)));
  for (size_t i = 0; i < points.size(); ++i) {
    points[i].x = p.at(i, 0), points[i].y = p.at(i, 1), points[i].z = p.at(i, 2);
    if (!std::isfinite(points[i].x) || !std::isfinite(points[i].y) || !std::isfinite(points[i].z))
      throw ValueError("lidar_classify: points[" + std::to_string(i) + "] is not finite");
    points[i].classification = c.at(i);
  }
  return points;
}

py::dict lidar_classify(const py::object& las, const py::object& points, const py::object& classification,
                        double cell_m, double t_s, const py::object& areas) {
  lidar::BuiltUpOptions o;
  o.cell_m = cell_m;
  o.t_s = t_s;
  if (!areas.is_none()) {
    const auto a = areas.cast<std::vector<double>>();
    if (a.size() != 3) throw ValueError("lidar_classify: areas must be (a1, a2, a3) in m^2");
    o.areas = {a[0], a[1], a[2]};
  }
  lidar::validate(o);
  if (las.is_none() == points.is_none()) throw ValueError("lidar_classify: give either las or points");
  std::vector<std::string> files;
  std::vector<LasPoint> cloud;
  if (!las.is_none()) {
    files = py::isinstance<py::str>(las) ? std::vector<std::string>{las.cast<std::string>()}
                                         : las.cast<std::vector<std::string>>();
    if (files.empty()) throw ValueError("lidar_classify: no LAS file given");
  } else {
    cloud = points_from_arrays(points, classification);
    if (cloud.empty()) throw ValueError("lidar_classify: no points");
  }
  lidar::BuiltUp b;
  lidar::Grid grid;
  {
    py::gil_scoped_release release;
    lidar::CellRaster raster;
    if (!files.empty()) {
      grid = lidar::grid_of_files(files, o.cell_m);
      raster = lidar::rasterise_files(files, grid, o.classes, false, lidar::OutsideGrid::refuse);
    } else {
      double x0 = cloud[0].x, y0 = cloud[0].y, x1 = x0, y1 = y0;
      for (const LasPoint& p : cloud)
        x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x), y1 = std::max(y1, p.y);
      grid = lidar::grid_over(x0, y0, x1, y1, o.cell_m);
      raster = lidar::CellRaster(grid);
      raster.add(cloud, o.classes);
    }
    b = lidar::classify_built_up(raster, o);
  }
  py::dict d;
  d["classes"] = image_to_array(b.profile.classes);
  d["building"] = image_to_array(b.s);
  d["height_m"] = image_to_array(b.height_m);
  d["grid"] = grid_to_python(grid);
  d["buildings"] = b.buildings.count;
  py::dict stats;
  for (int k = 0; k < lidar::kBuiltUpClasses; ++k) {
    const lidar::ClassStatistics& s = b.profile.stats[size_t(k)];
    py::dict one;
    one["cells"] = s.cells;
    one["components"] = s.components;
    one["settlements"] = s.settlements;
    stats[lidar::class_name(static_cast<lidar::BuiltUpClass>(k + 1))] = one;
  }
  d["stats"] = stats;
  return d;
}

py::dict synthetic_settlements(double cell_m, std::uint64_t seed) {
  lidar::SyntheticSettlements s;
  {
    py::gil_scoped_release release;
    s = lidar::synthetic_settlements({cell_m, seed, 0, 0});
  }
  py::array_t<double> xyz({py::ssize_t(s.points.size()), py::ssize_t(3)});
  py::array_t<std::uint8_t> codes(py::ssize_t(s.points.size()));
  auto x = xyz.mutable_unchecked<2>();
  auto c = codes.mutable_unchecked<1>();
  for (size_t i = 0; i < s.points.size(); ++i) {
    x(i, 0) = s.points[i].x, x(i, 1) = s.points[i].y, x(i, 2) = s.points[i].z;
    c(i) = s.points[i].classification;
  }
  py::dict d;
  d["points"] = xyz;
  d["classification"] = codes;
  d["grid"] = grid_to_python(s.grid);
  d["footprints"] = image_to_array(s.footprints);
  d["classes"] = image_to_array(s.classes);
  d["areas"] = py::make_tuple(s.areas.a1, s.areas.a2, s.areas.a3);
  d["t_s"] = s.t_s;
  d["buildings"] = s.buildings;
  return d;
}

}  // namespace

void bind_lidar(py::module_& m) {
  m.def("lidar_classify", &lidar_classify, py::kw_only(), py::arg("las") = py::none(), py::arg("points") = py::none(),
        py::arg("classification") = py::none(), py::arg("cell_m") = 0.5, py::arg("t_s") = 2.0,
        py::arg("areas") = py::none(),
        "built-up areas of LAS file(s) (las: a path or a list) or of points (N, 3) metres with LAS classification "
        "codes (N,) (6 building, 2 ground) -> dict: classes (H, W) uint8 (0 none, 1 hamlet .. 4 city; row 0 north), "
        "building (S), height_m, grid, buildings, stats per class {cells, components, settlements}; areas: "
        "(a1, a2, a3) m^2, default the paper's");
  m.def("synthetic_settlements", &synthetic_settlements, py::arg("cell_m") = 1.0, py::arg("seed") = 1,
        "the synthetic hamlet / village / hamlet / town / city with their exact classes at t_s -> dict: points, "
        "classification, grid, footprints, classes, areas, t_s, buildings");
}

}  // namespace hf::python
