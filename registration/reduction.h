// Reduction backends: evaluate one level's per-pixel rows (registration/kernels/residuals.h) and reduce them to
// the 29 values of the normal equations (order in registration/kernels/reg_common.h).
//
//   auto backend = hf::make_backend("cpu");             // or "opencl"
//   hf::NormalEquations ne = backend->reduce(problem);  // H = ne.JtJ, g = ne.Jtr; solve H xi = -g
//
// The Gauss-Newton driver (registration/gauss_newton.h) owns everything else; a backend only sums.
// Thread-safety: a backend object is used by one thread at a time (reduce() may use many threads inside).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/se3.h"
#include "registration/kernels/reg_common.h"

namespace hf {

// The normal equations of one Gauss-Newton iteration: JtJ = sum w J^T J (symmetric), Jtr = sum w J^T r,
// cost = sum w r^2, count = number of rows (residuals with a correspondence).
struct NormalEquations {
  Matrix6d JtJ = Matrix6d::Zero();
  Vector6d Jtr = Vector6d::Zero();
  double cost = 0.0;
  long count = 0;

  // From the 29 sums in the documented order; the lower triangle of JtJ is mirrored from the upper.
  static NormalEquations from_sums(const double* sums);
  // The 29 sums back (for tests and for backends that combine partial results).
  std::vector<double> to_sums() const;
};

// One level's inputs for one method. All maps are camera.width x camera.height, row-major, and are owned by the
// caller (they must outlive reduce()). Frames: see registration/kernels/reg_common.h (v = T_ref_cur v_cur).
struct ResidualProblem {
  hf_intrinsics camera{};  // intrinsics and size of this level (shared by the current and the reference maps)
  // Current frame (t+1).
  const hf_float4* cur_vertices = nullptr;  // camera frame, metres, w = 1 valid
  const hf_float4* cur_normals = nullptr;   // unit, w = 1 valid
  const float* cur_intensity = nullptr;     // [0, 1]
  // Reference frame (t): model maps or the previous frame.
  const hf_float4* ref_vertices = nullptr;
  const hf_float4* ref_normals = nullptr;
  const float* ref_intensity = nullptr;
  const float* ref_grad_x = nullptr;  // intensity units per pixel
  const float* ref_grad_y = nullptr;
  hf_transform12 T_ref_cur{};  // the current estimate (rotation row-major, then translation)
  hf_reg_params params{};      // method, rejection thresholds, term weights, robust kernels and scales
  // Changes whenever any map pointer or its contents change (the driver bumps it per registration call and
  // level); constant across the iterations of one level, so a backend may keep uploaded copies while it matches.
  std::uint64_t inputs_version = 0;

  int width() const { return camera.width; }
  int height() const { return camera.height; }
};

// hf_transform12 of an SE3 (float).
hf_transform12 to_transform12(const SE3& T);

class ReductionBackend {
 public:
  virtual ~ReductionBackend() = default;
  // The reduced normal equations of `problem`. Throws hf::Error only for a malformed problem (null map that the
  // method reads, non-positive size) or a device failure; the driver turns exceptions into a failed result.
  virtual NormalEquations reduce(const ResidualProblem& problem) = 0;
  virtual std::string name() const = 0;  // "cpu", "opencl"
};

// The backend registry: "cpu" (default, always available) or "opencl". Throws hf::Error naming the known backends
// for an unknown name, and hf::Error "OpenCL backend not built" when the OpenCL target is not linked (or the
// OpenCL factory's own error when no platform/device is present).
std::unique_ptr<ReductionBackend> make_backend(const std::string& name = "cpu");
std::vector<std::string> backend_names();

// Checks the pointers the method reads and the size; throws hf::Error naming the problem.
void validate_problem(const ResidualProblem& problem);

}  // namespace hf
