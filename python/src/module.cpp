// The `hashfusion` Python module (import hashfusion as hf): the module, its exceptions, and the value types
// (cameras, SE3 as 4x4 arrays, frames, meshes, trajectories). The pipeline, datasets, registration and
// evaluation are bound in bind_slam.cpp. Conventions of every conversion: python/src/convert.h.
//
// Errors: hf::Error -> hashfusion.Error (a RuntimeError), hf::ParseError -> hashfusion.ParseError and
// fusion::CapacityError -> hashfusion.CapacityError (both subclasses of hashfusion.Error), bad arguments ->
// ValueError; each carries the C++ message.
#include <pybind11/eigen.h>
#include <pybind11/operators.h>
#include <pybind11/stl.h>

#include <cstring>

#include "core/camera.h"
#include "core/camera_bounds.h"
#include "core/error.h"
#include "fusion/voxel_block_grid.h"
#include "io/frame_source.h"
#include "io/mesh.h"
#include "io/mesh_file.h"
#include "io/ply.h"
#include "python/src/bindings.h"
#include "python/src/convert.h"

namespace hf::python {
namespace {

void bind_errors(py::module_& m) {
  static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
  static py::exception<ParseError> parse_error(m, "ParseError", error.ptr());
  static py::exception<fusion::CapacityError> capacity_error(m, "CapacityError", error.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const ValueError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const fusion::CapacityError& e) {
      capacity_error(e.what());
    } catch (const ParseError& e) {
      parse_error(e.what());
    } catch (const Error& e) {
      error(e.what());
    }
  });
}

// The bounds a camera file is held to (core/camera_bounds.h), at the call: Camera(fx=nan) or fx=-525 would
// otherwise construct and fail frames later naming a derived camera.
PinholeCamera checked_camera(const PinholeCamera& c) {
  if (c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384)
    throw ValueError("Camera: width and height must be within 1..16384, got " + std::to_string(c.width) + "x" +
                     std::to_string(c.height));
  try {
    check_camera_intrinsics(c, "Camera");
  } catch (const ParseError& e) {
    throw ValueError(e.what());
  }
  return c;
}

// A read-write attribute whose new value is checked with the whole camera (the old value kept on error).
template <class T>
void camera_field(py::class_<PinholeCamera>& cls, const char* name, T PinholeCamera::*field) {
  cls.def_property(
      name, [field](const PinholeCamera& c) { return c.*field; },
      [field](PinholeCamera& c, T value) {
        PinholeCamera changed = c;
        changed.*field = value;
        c = checked_camera(changed);
      });
}

void bind_camera(py::module_& m) {
  py::class_<PinholeCamera> cls(m, "Camera", "Pinhole camera (pixels: x right, y down, centres at integers; "
                                             "metres); fx, fy, cx, cy checked as a camera file's are");
  cls.def(py::init([](double fx, double fy, double cx, double cy, int width, int height) {
            return checked_camera(PinholeCamera{fx, fy, cx, cy, width, height});
          }),
          py::arg("fx") = 525.0, py::arg("fy") = 525.0, py::arg("cx") = 319.5, py::arg("cy") = 239.5,
          py::arg("width") = 640, py::arg("height") = 480);
  camera_field(cls, "fx", &PinholeCamera::fx);
  camera_field(cls, "fy", &PinholeCamera::fy);
  camera_field(cls, "cx", &PinholeCamera::cx);
  camera_field(cls, "cy", &PinholeCamera::cy);
  camera_field(cls, "width", &PinholeCamera::width);
  camera_field(cls, "height", &PinholeCamera::height);
  cls
      .def_property_readonly("K", &PinholeCamera::K, "3x3 intrinsic matrix")
      .def("scaled", &PinholeCamera::scaled, py::arg("level"), "the camera of pyramid level `level`")
      .def_static("preset", &PinholeCamera::preset, py::arg("name"))
      .def_static("preset_names", &PinholeCamera::preset_names)
      .def_static("load",
                  [](const std::string& path) {
                    require_existing_path(path, "Camera.load");
                    return PinholeCamera::load(path);
                  },
                  py::arg("path"), "camera file (JSON or key-value text)")
      .def("save", &PinholeCamera::save, py::arg("path"), "writes the JSON form atomically")
      .def("describe", &PinholeCamera::describe)
      .def(py::self == py::self)
      .def("__repr__", [](const PinholeCamera& c) { return "hashfusion.Camera(" + c.describe() + ")"; })
      .def(py::pickle(
          [](const PinholeCamera& c) { return py::make_tuple(c.fx, c.fy, c.cx, c.cy, c.width, c.height); },
          [](const py::tuple& t) {
            return checked_camera(PinholeCamera{t[0].cast<double>(), t[1].cast<double>(), t[2].cast<double>(),
                                                t[3].cast<double>(), t[4].cast<int>(), t[5].cast<int>()});
          }));
}

void bind_se3(py::module_& m) {
  m.def("se3_exp", [](const Vector6d& xi) { return se3_to_array(SE3::exp(xi)); }, py::arg("xi"),
        "4x4 transform exp(xi), xi = (omega, v) (rotation first)");
  m.def("se3_log", [](const py::object& T) { return Vector6d(se3_from_array(T, "T").log()); }, py::arg("T"),
        "xi = (omega, v) of a 4x4 transform");
  m.def("se3_normalize", [](const py::object& T) { return se3_to_array(se3_from_array(T, "T")); }, py::arg("T"),
        "a 4x4 transform through hashfusion's SE3 (checked, rotation snapped to the nearest one)");
}

void bind_frame(py::module_& m) {
  py::class_<RgbdFrame>(m, "Frame", "One RGB-D frame: depth float32 (H, W) metres, colour uint8 (H, W, 3) RGB")
      .def(py::init([](const py::object& depth, const py::object& color, double timestamp,
                       const py::object& T_world_camera_gt, const py::object& depth_scale) {
             RgbdFrame f = frame_from_arrays(depth, color, timestamp, T_world_camera_gt, 0, depth_scale);
             if (f.depth.width() != f.color.width() || f.depth.height() != f.color.height())
               throw ValueError("Frame: depth and color differ in size");
             return f;
           }),
           py::arg("depth"), py::arg("color"), py::arg("timestamp") = 0.0, py::arg("T_world_camera_gt") = py::none(),
           py::arg("depth_scale") = py::none(),
           "depth: float32 (H, W) metres, or uint16 with depth_scale units per metre (1000: millimetres, 5000: "
           "TUM); color uint8 (H, W, 3) RGB; timestamp seconds (finite)")
      .def_property_readonly("depth", [](py::object self) { return depth_view(self.cast<RgbdFrame&>().depth, self); })
      .def_property_readonly("color", [](py::object self) { return color_view(self.cast<RgbdFrame&>().color, self); })
      .def_readonly("timestamp", &RgbdFrame::timestamp_s)
      .def_readonly("index", &RgbdFrame::index)
      .def_property_readonly("T_world_camera_gt",
                             [](const RgbdFrame& f) -> py::object {
                               if (!f.T_world_camera_gt) return py::none();
                               return se3_to_array(*f.T_world_camera_gt);
                             })
      .def_readonly("depth_file", &RgbdFrame::depth_file)
      .def_readonly("color_file", &RgbdFrame::color_file)
      .def("__repr__", [](const RgbdFrame& f) {
        return "hashfusion.Frame(index=" + std::to_string(f.index) + ", timestamp=" + std::to_string(f.timestamp_s) +
               ", " + std::to_string(f.depth.width()) + "x" + std::to_string(f.depth.height()) + ")";
      });
}

template <class T, class Scalar>
py::array_t<Scalar> rows_view(const std::vector<T>& rows, py::handle owner) {
  static_assert(sizeof(T) == 3 * sizeof(Scalar), "three packed scalars per row");
  const py::ssize_t n = py::ssize_t(rows.size());
  if (n == 0) return py::array_t<Scalar>(std::vector<py::ssize_t>{0, 3});
  return py::array_t<Scalar>({n, py::ssize_t(3)}, {py::ssize_t(sizeof(T)), py::ssize_t(sizeof(Scalar))},
                             reinterpret_cast<const Scalar*>(rows.data()), owner);
}

// An (N, 3) array of `type` ("Mesh", "PointCloud") argument `what`, converted to Scalar.
template <class T, class Scalar>
std::vector<T> rows_from(const py::handle& h, const char* type, const char* what) {
  auto a = py::array_t<Scalar, py::array::c_style | py::array::forcecast>::ensure(h);
  if (!a || a.ndim() != 2 || a.shape(1) != 3)
    throw ValueError(std::string(type) + ": " + what + " must be an (N, 3) array");
  std::vector<T> rows(size_t(a.shape(0)));
  if (!rows.empty()) std::memcpy(static_cast<void*>(rows.data()), a.data(), rows.size() * sizeof(T));
  return rows;
}

// Colours are uint8 only: a float array in [0, 1] cast to uint8 would silently become black.
std::vector<Rgb8> colors_from(const py::object& colors, const char* type) {
  py::array c = py::array::ensure(colors);
  if (!c || !c.dtype().is(py::dtype::of<std::uint8_t>()))
    throw ValueError(std::string(type) + ": colors must be a uint8 (N, 3) array");
  return rows_from<Rgb8, std::uint8_t>(c, type, "colors");
}

void bind_mesh(py::module_& m) {
  py::class_<TriangleMesh>(m, "Mesh",
                           "Triangle mesh: vertices float32 (N, 3) metres, faces int32 (M, 3) counter-clockwise, "
                           "colors uint8 (N, 3) or (0, 3), normals float32 (N, 3) or (0, 3); views, no copies")
      .def(py::init([](const py::object& vertices, const py::object& faces, const py::object& colors,
                       const py::object& normals) {
             TriangleMesh mesh;
             mesh.vertices = rows_from<Eigen::Vector3f, float>(vertices, "Mesh", "vertices");
             mesh.triangles = rows_from<Eigen::Vector3i, int>(faces, "Mesh", "faces");
             if (!colors.is_none()) mesh.colors = colors_from(colors, "Mesh");
             if (!normals.is_none()) mesh.normals = rows_from<Eigen::Vector3f, float>(normals, "Mesh", "normals");
             mesh.validate();
             return mesh;
           }),
           py::arg("vertices"), py::arg("faces"), py::arg("colors") = py::none(), py::arg("normals") = py::none())
      .def_property_readonly("vertices", [](py::object s) {
        return rows_view<Eigen::Vector3f, float>(s.cast<TriangleMesh&>().vertices, s);
      })
      .def_property_readonly("faces", [](py::object s) {
        return rows_view<Eigen::Vector3i, int>(s.cast<TriangleMesh&>().triangles, s);
      })
      .def_property_readonly("colors", [](py::object s) {
        return rows_view<Rgb8, std::uint8_t>(s.cast<TriangleMesh&>().colors, s);
      })
      .def_property_readonly("normals", [](py::object s) {
        return rows_view<Eigen::Vector3f, float>(s.cast<TriangleMesh&>().normals, s);
      })
      .def("save", [](const TriangleMesh& mesh, const std::string& path) { write_ply(path, mesh); }, py::arg("path"),
           "binary PLY, written atomically")
      .def("__repr__", [](const TriangleMesh& mesh) {
        return "hashfusion.Mesh(" + std::to_string(mesh.vertices.size()) + " vertices, " +
               std::to_string(mesh.triangles.size()) + " faces)";
      });
  m.def("load_mesh",
        [](const std::string& path) {
          require_existing_path(path, "load_mesh");
          return read_mesh_file(path);
        },
        py::arg("path"), "reads a PLY (ASCII or binary) or OBJ mesh, by the file's extension");
}

void bind_point_cloud(py::module_& m) {
  py::class_<PointCloud>(m, "PointCloud",
                         "Point cloud: points float32 (N, 3) metres, colors uint8 (N, 3) or (0, 3), normals float32 "
                         "(N, 3) or (0, 3); views, no copies")
      .def(py::init([](const py::object& points, const py::object& colors, const py::object& normals) {
             PointCloud cloud;
             cloud.positions = rows_from<Eigen::Vector3f, float>(points, "PointCloud", "points");
             if (!colors.is_none()) cloud.colors = colors_from(colors, "PointCloud");
             if (!normals.is_none())
               cloud.normals = rows_from<Eigen::Vector3f, float>(normals, "PointCloud", "normals");
             cloud.validate();
             return cloud;
           }),
           py::arg("points"), py::arg("colors") = py::none(), py::arg("normals") = py::none())
      .def_property_readonly("points", [](py::object s) {
        return rows_view<Eigen::Vector3f, float>(s.cast<PointCloud&>().positions, s);
      })
      .def_property_readonly("colors", [](py::object s) {
        return rows_view<Rgb8, std::uint8_t>(s.cast<PointCloud&>().colors, s);
      })
      .def_property_readonly("normals", [](py::object s) {
        return rows_view<Eigen::Vector3f, float>(s.cast<PointCloud&>().normals, s);
      })
      .def("__len__", &PointCloud::size)
      .def("save", [](const PointCloud& cloud, const std::string& path) { write_ply(path, cloud); }, py::arg("path"),
           "binary PLY, written atomically")
      .def("__repr__", [](const PointCloud& cloud) {
        return "hashfusion.PointCloud(" + std::to_string(cloud.size()) + " points" +
               (cloud.has_colors() ? ", colors" : "") + (cloud.has_normals() ? ", normals" : "") + ")";
      });
  m.def("load_point_cloud",
        [](const std::string& path) {
          require_existing_path(path, "load_point_cloud");
          return read_ply_point_cloud(path);
        },
        py::arg("path"), "reads a PLY point cloud (ASCII or binary; a mesh's vertices when it has faces)");
}

void bind_trajectory(py::module_& m) {
  m.def("read_trajectory",
        [](const std::string& path) {
          require_existing_path(path, "read_trajectory");
          return trajectory_to_python(read_tum_trajectory(path));
        },
        py::arg("path"), "TUM trajectory file -> (stamps (N,), poses (N, 4, 4) T_world_camera)");
  m.def("write_trajectory",
        [](const std::string& path, const py::object& trajectory) {
          write_tum_trajectory(path, trajectory_from_python(trajectory, "trajectory"));
        },
        py::arg("path"), py::arg("trajectory"), "writes (stamps, poses) as a TUM file, full precision, atomically");
}

}  // namespace
}  // namespace hf::python

PYBIND11_MODULE(_hashfusion, m) {
  using namespace hf::python;
  m.doc() = "hashfusion: voxel-hashed TSDF RGB-D SLAM (native part; import hashfusion)";
  m.attr("__version__") = HF_VERSION;
  bind_errors(m);
  bind_camera(m);
  bind_se3(m);
  bind_frame(m);
  bind_mesh(m);
  bind_point_cloud(m);
  bind_trajectory(m);
  bind_slam(m);
  bind_head(m);
  bind_lidar(m);
  bind_photogrammetry(m);
}
