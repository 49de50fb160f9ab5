// Conversions between hashfusion's C++ values and the Python side of the `hashfusion` module.
//
// Python sees plain numpy arrays and dicts:
//   SE3              4x4 float64 array (homogeneous T_a_b); in: any array-like of shape (4, 4), finite, bottom row
//                    (0, 0, 0, 1) and an orthonormal rotation block to 1e-6 (SE3::from_matrix then snaps it to the
//                    nearest rotation); anything else is a ValueError naming the argument.
//   DepthImage       float32 (H, W) in metres, 0 = no measurement.
//   ColorImage       uint8 (H, W, 3), RGB.
//   Trajectory       (stamps float64 (N,), poses float64 (N, 4, 4)) tuple, or the path of a TUM trajectory file.
//   nlohmann::json   dict / list / str / int / float / bool / None.
// Arrays coming out of C++ own their memory (the C++ image is moved into the array's base: no copy); arrays going
// in are copied once into the owning C++ image (hashfusion's images own their pixels).
// Every function here needs the GIL.
#pragma once

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <nlohmann/json.hpp>
#include <string>

#include "core/image.h"
#include "core/se3.h"
#include "io/frame_source.h"
#include "io/trajectory_io.h"

namespace hf::python {

namespace py = pybind11;

// Raised as Python's ValueError with the message (registered in module.cpp).
struct ValueError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

SE3 se3_from_array(const py::handle& array, const char* what);
py::array_t<double> se3_to_array(const SE3& T);

DepthImage depth_from_array(const py::handle& array, const char* what);
ColorImage color_from_array(const py::handle& array, const char* what);
// Zero-copy views: the image moves into the returned array's base object.
py::array_t<float> depth_to_array(DepthImage&& depth);
py::array_t<std::uint8_t> color_to_array(ColorImage&& color);
// Views into memory that `owner` keeps alive (e.g. a Frame's images).
py::array_t<float> depth_view(const DepthImage& depth, const py::handle& owner);
py::array_t<std::uint8_t> color_view(const ColorImage& color, const py::handle& owner);

// A frame from its arrays (depth, colour as above; T_world_camera_gt None or a 4x4 pose); sizes are the caller's
// to check (the pipeline checks them against its camera).
RgbdFrame frame_from_arrays(const py::handle& depth, const py::handle& color, double timestamp,
                            const py::handle& T_world_camera_gt, size_t index);

Trajectory trajectory_from_python(const py::handle& value, const char* what);
py::tuple trajectory_to_python(const Trajectory& trajectory);

nlohmann::json json_from_python(const py::handle& value, const std::string& where);
py::object json_to_python(const nlohmann::json& j);

}  // namespace hf::python
