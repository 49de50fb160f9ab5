#include "python/src/convert.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <sstream>
#include <system_error>
#include <vector>

#include "io/trajectory_io.h"

namespace hf::python {
namespace {

constexpr double kRotationTolerance = 1e-6;  // |R^T R - I| and |bottom row - (0 0 0 1)|, max entry

std::string str(const py::handle& h) { return py::str(py::type::handle_of(h).attr("__name__")); }

// A C-contiguous array of T converted from anything numpy can convert; ValueError naming `what` otherwise.
template <class T>
py::array_t<T, py::array::c_style | py::array::forcecast> as_array(const py::handle& h, const char* what,
                                                                    const char* expected) {
  auto a = py::array_t<T, py::array::c_style | py::array::forcecast>::ensure(h);
  if (!a) throw ValueError(std::string(what) + ": expected " + expected + ", got " + str(h));
  return a;
}

std::string shape_of(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += (i ? ", " : "") + std::to_string(a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

void check_image_size(const py::array& a, const char* what) {
  if (a.shape(0) < 1 || a.shape(1) < 1 || a.shape(0) > 1 << 15 || a.shape(1) > 1 << 15)
    throw ValueError(std::string(what) + ": image size " + shape_of(a) + " outside 1 .. 32768 pixels a side");
}

template <class ImageT, class Pixel>
py::array_t<Pixel> image_array(ImageT* image, py::handle base, std::vector<py::ssize_t> shape,
                               std::vector<py::ssize_t> strides) {
  if (image->empty()) {  // no pixels to point at: a fresh (0, 0[, 3]) array
    shape[0] = shape[1] = 0;
    return py::array_t<Pixel>(shape);
  }
  return py::array_t<Pixel>(shape, strides, reinterpret_cast<const Pixel*>(image->data()), base);
}

}  // namespace

namespace {

// The checks of se3_from_array on T = `values` (16 doubles, row-major).
SE3 se3_from_values(const double* values, const char* what) {
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) {
      T(r, c) = values[4 * r + c];
      if (!std::isfinite(T(r, c))) throw ValueError(std::string(what) + ": non-finite entry");
    }
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const double row_error = (T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff();
  const double orth_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (row_error > kRotationTolerance)
    throw ValueError(std::string(what) + ": bottom row is not (0, 0, 0, 1)");
  if (orth_error > kRotationTolerance || R.determinant() < 0.0)
    throw ValueError(std::string(what) + ": the upper-left 3x3 block is not a rotation (|R^T R - I| = " +
                     std::to_string(orth_error) + ", det " + std::to_string(R.determinant()) + ")");
  return SE3::from_matrix(T);
}

}  // namespace

SE3 se3_from_array(const py::handle& array, const char* what) {
  auto a = as_array<double>(array, what, "a 4x4 array");
  if (a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4)
    throw ValueError(std::string(what) + ": expected a 4x4 array, got shape " + shape_of(a));
  return se3_from_values(a.data(), what);
}

py::array_t<double> se3_to_array(const SE3& T) {
  py::array_t<double> a({4, 4});
  const Eigen::Matrix4d m = T.matrix();
  auto v = a.mutable_unchecked<2>();
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) v(r, c) = m(r, c);
  return a;
}

namespace {

constexpr const char* kDepthExpected =
    "expected float32 metres, or uint16 with depth_scale (units per metre: 1000 for millimetres as Open3D reads "
    "PNGs, 5000 for TUM RGB-D)";

// The median of the measured (> 0) pixels, 0 when there are none.
float depth_median_m(const DepthImage& depth) {
  std::vector<float> valid;
  valid.reserve(depth.size());
  for (size_t i = 0; i < depth.size(); ++i)
    if (depth.data()[i] > 0.0f) valid.push_back(depth.data()[i]);
  if (valid.empty()) return 0.0f;
  auto mid = valid.begin() + long(valid.size() / 2);
  std::nth_element(valid.begin(), mid, valid.end());
  return *mid;
}

std::string depth_number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

}  // namespace

DepthImage depth_from_array(const py::handle& array, const char* what, const py::handle& depth_scale) {
  py::array any = py::array::ensure(array);
  if (!any) throw ValueError(std::string(what) + ": " + kDepthExpected + ", got " + str(array));
  const bool is_float = any.dtype().is(py::dtype::of<float>());
  const bool is_u16 = any.dtype().is(py::dtype::of<std::uint16_t>());
  if (!is_float && !is_u16)
    throw ValueError(std::string(what) + ": " + kDepthExpected + ", got a " + std::string(py::str(any.dtype())) +
                     " array of shape " + shape_of(any));
  if (any.ndim() != 2) throw ValueError(std::string(what) + ": expected shape (H, W), got " + shape_of(any));
  check_image_size(any, what);
  DepthImage depth(int(any.shape(1)), int(any.shape(0)));
  if (is_float) {
    if (!depth_scale.is_none())
      throw ValueError(std::string(what) + ": depth_scale applies to uint16 depth; float32 depth is metres already");
    auto a = as_array<float>(any, what, kDepthExpected);
    const float* src = a.data();
    for (size_t i = 0; i < depth.size(); ++i) {
      if (!std::isfinite(src[i]) || src[i] < 0.0f)
        throw ValueError(std::string(what) + ": pixel (" + std::to_string(i % depth.width()) + ", " +
                         std::to_string(i / depth.width()) + ") is " + std::to_string(src[i]) +
                         "; depth is metres >= 0, with 0 for no measurement");
      depth.data()[i] = src[i];
    }
  } else {
    if (depth_scale.is_none())
      throw ValueError(std::string(what) + ": uint16 depth of shape " + shape_of(any) +
                       " needs depth_scale, its units per metre (1000 for millimetres as Open3D reads PNGs, 5000 "
                       "for TUM RGB-D); it is not guessed");
    const double scale = py::float_(py::reinterpret_borrow<py::object>(depth_scale)).cast<double>();
    if (!std::isfinite(scale) || scale <= 0.0)
      throw ValueError(std::string(what) + ": depth_scale must be a finite number > 0 (units per metre), got " +
                       depth_number(scale));
    auto a = as_array<std::uint16_t>(any, what, kDepthExpected);
    const std::uint16_t* src = a.data();
    for (size_t i = 0; i < depth.size(); ++i) depth.data()[i] = float(double(src[i]) / scale);
  }
  const float median = depth_median_m(depth);
  if (median > kMaxPlausibleMedianDepthM)
    throw ValueError(std::string(what) + ": median depth " + depth_number(median) + " m is beyond " +
                     depth_number(kMaxPlausibleMedianDepthM) +
                     " m, implausible for an RGB-D sensor: are the values millimetres or TUM units? Pass them as "
                     "uint16 with depth_scale=1000 (millimetres) or 5000 (TUM), or divide to metres first");
  return depth;
}

void require_existing_path(const std::string& path, const char* what) {
  std::error_code ec;
  if (std::filesystem::exists(std::filesystem::path(path), ec) || ec) return;  // errors other than "absent": C++'s
  py::object error = py::module_::import("builtins")
                         .attr("FileNotFoundError")(ENOENT, std::string(what) + ": no such file or folder", path);
  PyErr_SetObject(reinterpret_cast<PyObject*>(Py_TYPE(error.ptr())), error.ptr());
  throw py::error_already_set();
}

ColorImage color_from_array(const py::handle& array, const char* what) {
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be three packed bytes for the (H, W, 3) view");
  py::array any = py::array::ensure(array);
  if (!any) throw ValueError(std::string(what) + ": expected a uint8 (H, W, 3) array, got " + str(array));
  if (!any.dtype().is(py::dtype::of<std::uint8_t>()))
    throw ValueError(std::string(what) + ": expected dtype uint8, got " + std::string(py::str(any.dtype())));
  auto a = as_array<std::uint8_t>(any, what, "a uint8 (H, W, 3) array");
  if (a.ndim() != 3 || a.shape(2) != 3)
    throw ValueError(std::string(what) + ": expected shape (H, W, 3), got " + shape_of(a));
  check_image_size(a, what);
  ColorImage color(int(a.shape(1)), int(a.shape(0)));
  std::memcpy(static_cast<void*>(color.data()), a.data(), color.size() * 3);
  return color;
}

py::array_t<float> depth_to_array(DepthImage&& depth) {
  auto* owned = new DepthImage(std::move(depth));
  py::capsule base(owned, [](void* p) { delete static_cast<DepthImage*>(p); });
  return depth_view(*owned, base);
}

py::array_t<std::uint8_t> color_to_array(ColorImage&& color) {
  auto* owned = new ColorImage(std::move(color));
  py::capsule base(owned, [](void* p) { delete static_cast<ColorImage*>(p); });
  return color_view(*owned, base);
}

py::array_t<float> depth_view(const DepthImage& depth, const py::handle& owner) {
  const py::ssize_t w = depth.width(), h = depth.height();
  return image_array<const DepthImage, float>(&depth, owner, {h, w}, {w * py::ssize_t(sizeof(float)),
                                                                       py::ssize_t(sizeof(float))});
}

py::array_t<std::uint8_t> color_view(const ColorImage& color, const py::handle& owner) {
  const py::ssize_t w = color.width(), h = color.height();
  return image_array<const ColorImage, std::uint8_t>(&color, owner, {h, w, 3}, {w * 3, 3, 1});
}

RgbdFrame frame_from_arrays(const py::handle& depth, const py::handle& color, double timestamp,
                            const py::handle& T_world_camera_gt, size_t index, const py::handle& depth_scale) {
  if (!std::isfinite(timestamp))
    throw ValueError("timestamp: expected a finite time in seconds, got " + depth_number(timestamp));
  RgbdFrame f;
  f.index = index;
  f.timestamp_s = timestamp;
  f.depth = depth_from_array(depth, "depth", depth_scale);
  f.color = color_from_array(color, "color");
  if (!T_world_camera_gt.is_none()) f.T_world_camera_gt = se3_from_array(T_world_camera_gt, "T_world_camera_gt");
  return f;
}

Trajectory trajectory_from_python(const py::handle& value, const char* what) {
  if (py::isinstance<py::str>(value) || py::hasattr(value, "__fspath__")) {
    const std::string path = py::str(py::module_::import("os").attr("fspath")(value));
    require_existing_path(path, what);
    return read_tum_trajectory(path);
  }
  if (!py::isinstance<py::sequence>(value) || py::len(value) != 2)
    throw ValueError(std::string(what) + ": expected a TUM trajectory path or a (stamps, poses) pair, got " +
                     str(value));
  const py::sequence pair = py::reinterpret_borrow<py::sequence>(value);
  auto stamps = as_array<double>(pair[0], what, "stamps as a float64 (N,) array");
  auto poses = as_array<double>(pair[1], what, "poses as a float64 (N, 4, 4) array");
  if (stamps.ndim() != 1) throw ValueError(std::string(what) + ": stamps must have shape (N,), got " + shape_of(stamps));
  if (poses.ndim() != 3 || poses.shape(0) != stamps.shape(0) || poses.shape(1) != 4 || poses.shape(2) != 4)
    throw ValueError(std::string(what) + ": poses must have shape (" + std::to_string(stamps.shape(0)) +
                     ", 4, 4), got " + shape_of(poses));
  Trajectory t;
  t.reserve(size_t(stamps.shape(0)));
  const std::string pose_what = std::string(what) + " pose";
  for (py::ssize_t i = 0; i < stamps.shape(0); ++i) {
    const double s = stamps.at(i);
    if (!std::isfinite(s) || (i > 0 && s <= t.back().timestamp_s))
      throw ValueError(std::string(what) + ": stamp " + std::to_string(i) +
                       " is not finite or not above the one before (stamps must increase strictly)");
    t.push_back({s, se3_from_values(poses.data() + 16 * i, pose_what.c_str())});
  }
  return t;
}

py::tuple trajectory_to_python(const Trajectory& trajectory) {
  const py::ssize_t n = py::ssize_t(trajectory.size());
  py::array_t<double> stamps(n), poses({n, py::ssize_t(4), py::ssize_t(4)});
  auto s = stamps.mutable_unchecked<1>();
  auto p = poses.mutable_unchecked<3>();
  for (py::ssize_t i = 0; i < n; ++i) {
    s(i) = trajectory[size_t(i)].timestamp_s;
    const Eigen::Matrix4d m = trajectory[size_t(i)].T_world_camera.matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) p(i, r, c) = m(r, c);
  }
  return py::make_tuple(stamps, poses);
}

nlohmann::json json_from_python(const py::handle& v, const std::string& where) {
  if (v.is_none()) return nullptr;
  if (PyBool_Check(v.ptr())) return v.cast<bool>();
  if (PyLong_Check(v.ptr()) || (PyIndex_Check(v.ptr()) && !PyFloat_Check(v.ptr()))) {
    const py::int_ i = py::reinterpret_steal<py::int_>(PyNumber_Index(v.ptr()));
    if (!i) throw py::error_already_set();
    int overflow = 0;
    const long long x = PyLong_AsLongLongAndOverflow(i.ptr(), &overflow);
    if (overflow != 0) throw ValueError(where + ": integer out of the 64-bit range");
    return x;
  }
  if (PyFloat_Check(v.ptr()) || (PyNumber_Check(v.ptr()) && py::hasattr(v, "__float__")))
    return py::float_(py::reinterpret_borrow<py::object>(v)).cast<double>();
  if (py::isinstance<py::str>(v)) return v.cast<std::string>();
  if (py::isinstance<py::dict>(v)) {
    nlohmann::json j = nlohmann::json::object();
    for (auto item : py::reinterpret_borrow<py::dict>(v)) {
      if (!py::isinstance<py::str>(item.first))
        throw ValueError(where + ": dict keys must be str, got " + str(item.first));
      const std::string key = item.first.cast<std::string>();
      j[key] = json_from_python(item.second, where + "." + key);
    }
    return j;
  }
  if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v) || py::isinstance<py::array>(v)) {
    nlohmann::json j = nlohmann::json::array();
    size_t k = 0;
    for (auto item : py::reinterpret_borrow<py::iterable>(v))
      j.push_back(json_from_python(item, where + "[" + std::to_string(k++) + "]"));
    return j;
  }
  throw ValueError(where + ": unsupported value of type " + str(v) +
                   " (expected dict, list, str, int, float, bool or None)");
}

py::object json_to_python(const nlohmann::json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null: return py::none();
    case nlohmann::json::value_t::boolean: return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer: return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned: return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float: return py::float_(j.get<double>());
    case nlohmann::json::value_t::string: return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& e : j) l.append(json_to_python(e));
      return l;
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = json_to_python(it.value());
      return d;
    }
    default: return py::none();  // binary / discarded: never produced by hashfusion
  }
}

}  // namespace hf::python
