// Photogrammetric triangulation (photogrammetry/dlt_triangulation.h: Hartley-Zisserman's DLT, conditioned) of
// points observed in several shots given as 3x4 projection matrices (pixel ~ P [X; 1]).
#include <pybind11/eigen.h>
#include <pybind11/stl.h>

#include <Eigen/LU>

#include "photogrammetry/dlt_triangulation.h"
#include "python/src/bindings.h"
#include "python/src/convert.h"

namespace hf::python {
namespace {

using photogrammetry::Matrix34d;

// The centre of P = [M | p4]: C = -M^-1 p4, for a finite camera (M invertible), else a ValueError.
Eigen::Vector3d camera_centre(const Matrix34d& P, size_t k) {
  const Eigen::Matrix3d M = P.leftCols<3>();
  const Eigen::FullPivLU<Eigen::Matrix3d> lu(M);
  if (!P.allFinite() || lu.rank() < 3)
    throw ValueError("triangulate: cameras[" + std::to_string(k) + "] is not a finite camera (singular or non-finite)");
  return -lu.solve(P.col(3));
}

std::vector<Matrix34d> cameras_from_python(const py::handle& cameras) {
  auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(cameras);
  if (!a || a.ndim() != 3 || a.shape(1) != 3 || a.shape(2) != 4)
    throw ValueError("triangulate: cameras must be a (V, 3, 4) array of projection matrices");
  std::vector<Matrix34d> P(size_t(a.shape(0)));
  for (size_t k = 0; k < P.size(); ++k)
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) P[k](r, c) = a.at(k, r, c);
  return P;
}

py::dict triangulate(const py::object& pixels, const py::object& cameras, double min_angle_deg) {
  const std::vector<Matrix34d> P = cameras_from_python(cameras);
  auto x = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(pixels);
  const bool single = x && x.ndim() == 2;
  if (!x || (x.ndim() != 2 && x.ndim() != 3) || x.shape(x.ndim() - 2) != py::ssize_t(P.size()) ||
      x.shape(x.ndim() - 1) != 2)
    throw ValueError("triangulate: pixels must be (V, 2) or (N, V, 2) with V = the number of cameras");
  if (!std::isfinite(min_angle_deg) || min_angle_deg < 0)
    throw ValueError("triangulate: min_angle_deg must be finite and >= 0");
  std::vector<Eigen::Vector3d> C(P.size());
  for (size_t k = 0; k < P.size(); ++k) C[k] = camera_centre(P[k], k);
  const size_t n = single ? 1 : size_t(x.shape(0)), views = P.size();
  const double* data = x.data();
  for (size_t i = 0; i < n * views * 2; ++i)
    if (!std::isfinite(data[i])) throw ValueError("triangulate: pixels must be finite");
  std::vector<photogrammetry::Triangulation> results(n);
  {
    py::gil_scoped_release release;
    photogrammetry::DltOptions options;
    options.min_angle_deg = min_angle_deg;
    std::vector<photogrammetry::DltObservation> obs(views);
    for (size_t i = 0; i < n; ++i) {
      for (size_t k = 0; k < views; ++k)
        obs[k] = {P[k], C[k], Eigen::Vector2d(data[(i * views + k) * 2], data[(i * views + k) * 2 + 1])};
      results[i] = photogrammetry::triangulate_dlt(obs, options);
    }
  }
  // Not-ok points carry X = 0 and errors 0 (no NaN), their status says why.
  py::array_t<double> X({py::ssize_t(n), py::ssize_t(3)});
  py::array_t<double> errors({py::ssize_t(n), py::ssize_t(views)});
  py::array_t<double> angles{py::ssize_t(n)};
  auto Xm = X.mutable_unchecked<2>();
  auto em = errors.mutable_unchecked<2>();
  auto am = angles.mutable_unchecked<1>();
  py::list status;
  for (size_t i = 0; i < n; ++i) {
    const photogrammetry::Triangulation& t = results[i];
    for (int j = 0; j < 3; ++j) Xm(i, j) = t.X_world[j];
    for (size_t k = 0; k < views; ++k) em(i, k) = t.ok() ? t.reprojection_error_px[k] : 0.0;
    am(i) = t.max_angle_deg;
    status.append(photogrammetry::to_string(t.status));
  }
  py::dict d;
  if (single) {
    d["X"] = X.attr("reshape")(3);
    d["reprojection_error_px"] = errors.attr("reshape")(views);
    d["max_angle_deg"] = am(0);
    d["status"] = status[0];
  } else {
    d["X"] = X;
    d["reprojection_error_px"] = errors;
    d["max_angle_deg"] = angles;
    d["status"] = status;
  }
  return d;
}

}  // namespace

void bind_photogrammetry(py::module_& m) {
  m.def("triangulate", &triangulate, py::arg("pixels"), py::arg("cameras"), py::arg("min_angle_deg") = 0.1,
        "DLT triangulation (Hartley-Zisserman 12.2, conditioned): pixels (V, 2) of one point or (N, V, 2) of N "
        "points in the V shots whose projection matrices are cameras (V, 3, 4) -> dict: X (3,) / (N, 3) world, "
        "reprojection_error_px (V,) / (N, V), max_angle_deg, status ('ok', 'too_few_views', 'degenerate', "
        "'behind_camera'; X and errors 0 unless ok)");
}

}  // namespace hf::python
