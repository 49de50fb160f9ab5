// Conversions between hashfusion's C++ values and the Python side of the `hashfusion` module.
//
// Python sees plain numpy arrays and dicts:
//   SE3              4x4 float64 array (homogeneous T_a_b); in: any array-like of shape (4, 4), finite, bottom row
//                    (0, 0, 0, 1) and an orthonormal rotation block to 1e-6 (SE3::from_matrix then snaps it to the
//                    nearest rotation); anything else is a ValueError naming the argument.
//   DepthImage       float32 (H, W) in metres, 0 = no measurement; or uint16 (H, W) raw units with depth_scale units
//                    per metre (Open3D's convention: 1000 for millimetres, 5000 for TUM's PNGs; never guessed).
//                    Any other dtype is a ValueError naming dtype and shape, and so is a depth whose median valid
//                    value exceeds kMaxPlausibleMedianDepthM (raw units read as metres), with a hint about units.
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

// A median depth beyond this (metres) is millimetres or TUM units passed as metres: no RGB-D sensor the pipeline
// models sees that far (the Kinect noise model ends at 8 m; TUM's 14069 "m" was 2.8 m in units of 1/5000 m).
inline constexpr double kMaxPlausibleMedianDepthM = 20.0;

// depth_scale: None for float32 metres, units per metre (finite, > 0) for uint16.
DepthImage depth_from_array(const py::handle& array, const char* what, const py::handle& depth_scale = py::none());
ColorImage color_from_array(const py::handle& array, const char* what);
// Zero-copy views: the image moves into the returned array's base object.
py::array_t<float> depth_to_array(DepthImage&& depth);
py::array_t<std::uint8_t> color_to_array(ColorImage&& color);
// Views into memory that `owner` keeps alive (e.g. a Frame's images).
py::array_t<float> depth_view(const DepthImage& depth, const py::handle& owner);
py::array_t<std::uint8_t> color_view(const ColorImage& color, const py::handle& owner);

// A frame from its arrays (depth, colour as above; T_world_camera_gt None or a 4x4 pose); sizes are the caller's
// to check (the pipeline checks them against its camera).
// The timestamp must be finite (ValueError otherwise).
RgbdFrame frame_from_arrays(const py::handle& depth, const py::handle& color, double timestamp,
                            const py::handle& T_world_camera_gt, size_t index,
                            const py::handle& depth_scale = py::none());

// Raises Python's FileNotFoundError (errno ENOENT, filename = path) when nothing exists at `path`, so a missing
// input is told apart from a malformed one (hf.Error / hf.ParseError) as Python code expects.
void require_existing_path(const std::string& path, const char* what);

Trajectory trajectory_from_python(const py::handle& value, const char* what);
py::tuple trajectory_to_python(const Trajectory& trajectory);

nlohmann::json json_from_python(const py::handle& value, const std::string& where);
py::object json_to_python(const nlohmann::json& j);

}  // namespace hf::python
