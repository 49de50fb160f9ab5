// Frame registration: the `Registration` interface and its string-keyed registry.
//
//   auto reg = hf::make_registration("combined");          // "icp", "photometric", "combined"
//   hf::RegistrationResult res = reg->align(cur, ref, T_ref_cur_guess);
//   if (res.usable()) T_world_cur = T_world_ref * res.T_ref_cur;
//
// Frames (report eq. 10-11): the result T_ref_cur = delta_T maps points of the current camera (t+1) into the
// reference camera (t): p_ref = T_ref_cur * p_cur. For frame-to-frame tracking the reference is the previous frame;
// for frame-to-model tracking it is the raycast at the previous pose estimate, whose camera frame is then the
// previous camera, so T_world_cur = T_world_ref * T_ref_cur either way.
//
// Never throws from align() and never returns NaN/inf: invalid input, no data and numerical failure come back
// as a status with T_ref_cur = the initial guess.
// Thread-safety: one Registration object per thread (it owns its reduction backend).
#pragma once

#include <array>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/se3.h"
#include "registration/frame_pyramid.h"
#include "registration/reduction.h"

namespace hf {

enum class RegistrationStatus {
  good,        // converged, well conditioned, enough inliers
  poor,        // converged but few inliers or large residuals: usable with care
  degenerate,  // some directions are unconstrained; they kept the initial guess (see degenerate_dims)
  failed,      // diverged, lost correspondences or hit a numerical problem; T_ref_cur = the initial guess
  no_data,     // no valid pixels / correspondences at all; T_ref_cur = the initial guess
};
const char* to_string(RegistrationStatus status);

enum class RobustKernel { none, huber, student_t };

struct RegistrationResult {
  SE3 T_ref_cur;  // maps current-camera points into the reference camera (delta_T, eq. 10-11)
  RegistrationStatus status = RegistrationStatus::no_data;
  std::vector<int> iterations_per_level;  // [0] finest, as the pyramid; 0 for levels that were skipped
  double final_cost = 0.0;     // sum w r^2 / count at the last finest-level evaluation
  long inliers = 0;            // rows with a correspondence at the last finest-level evaluation
  double inlier_ratio = 0.0;   // inliers / (valid current pixels x rows per pixel), in [0, 1]
  Matrix6d information = Matrix6d::Zero();  // J^T W J at the solution (finest level), xi = (omega, v) order
  // Eigenvalues (ascending) and condition number (largest / smallest; 0 when singular, never inf) of the
  // information with rotations scaled to displacements at the RMS point distance L (S H S, S = diag(1/L x3, 1 x3)),
  // the matrix the degeneracy test uses.
  Vector6d eigenvalues = Vector6d::Zero();
  double condition_number = 0.0;
  int degenerate_dims = 0;     // eigen-directions below the degeneracy threshold (0..6)
  std::string message;         // why the status is not good (one line), empty otherwise

  bool usable() const {
    return status == RegistrationStatus::good || status == RegistrationStatus::poor ||
           status == RegistrationStatus::degenerate;
  }
};

// Settings of the Gauss-Newton driver (registration/gauss_newton.h) with the defaults of each method.
struct RegistrationOptions {
  // Iterations per pyramid level, [0] finest: KinectFusion's 4/5/10 coarse to fine. Its size is the number of
  // levels used (at most the pyramids' levels).
  std::vector<int> iterations = {10, 5, 4};
  // Convergence: stop a level when the step is below both (radians, metres).
  double min_step_rotation_rad = 1e-6;
  double min_step_translation_m = 1e-6;
  // Correspondence rejection (ICP): distance (all levels) and normal angle.
  float max_dist_m = 0.1f;          // KinectFusion: 10 cm
  float max_normal_angle_deg = 30.0f;
  // Robust weights (IRLS). Geometric residuals in metres, photometric in intensity units.
  RobustKernel robust_icp = RobustKernel::huber;
  float huber_icp_m = 0.01f;
  RobustKernel robust_rgb = RobustKernel::student_t;
  float huber_rgb = 0.05f;     // Huber k for photometric residuals
  float t_dof = 5.0f;          // DVO's nu
  // Student-t sigma of photometric residuals: re-estimated each iteration (DVO); this is the starting value and
  // the floor.
  float t_sigma_rgb_init = 0.05f;
  float t_sigma_rgb_min = 0.002f;
  float t_sigma_icp_m = 0.01f;  // fixed sigma when robust_icp = student_t
  // Weight lambda of photometric rows in `combined` (eq. 47-48); measured on TUM fr1 (bench/results).
  float rgb_weight = 0.1f;
  // Photometric: skip pixels whose reference |grad I| is below this (intensity per pixel; 1/255 = one grey level):
  // they carry no information, and a frame with almost none left is reported as poor (low inlier ratio).
  float min_gradient = 1.0f / 255.0f;
  bool photometric_occlusion_check = true;
  // Degeneracy (Zhang et al. 2016): eigen-directions with lambda_i < threshold * lambda_max are not updated.
  double degeneracy_threshold = 1e-3;
  // Outcome checks.
  long min_inliers = 64;              // fewer at the finest level: no_data (0 rows) or failed
  double poor_inlier_ratio = 0.3;     // below: poor
  double max_translation_m = 0.5;     // |t| of T_guess^-1 T_result beyond: failed (never a wild pose)
  double max_rotation_deg = 45.0;
  // The last finest-level step must be below these, else the estimate was still sliding: failed.
  double max_final_step_translation_m = 2e-4;
  double max_final_step_rotation_rad = 2e-4;

  // Throws hf::Error naming the first bad field.
  void validate() const;
};

class Registration {
 public:
  virtual ~Registration() = default;
  // Aligns the current pyramid to the reference pyramid starting from T_ref_cur_initial. Both pyramids must have
  // the same camera per level; photometric methods need intensity in both. Never throws.
  virtual RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                                   const SE3& T_ref_cur_initial) = 0;
  virtual std::string name() const = 0;
  virtual const RegistrationOptions& options() const = 0;
};

using RegistrationFactory =
    std::function<std::unique_ptr<Registration>(const RegistrationOptions&, std::unique_ptr<ReductionBackend>)>;

// Default options of a registered method (each method tunes its robust kernels); hf::Error for unknown names.
RegistrationOptions default_registration_options(const std::string& name);

// The registry. make_registration throws hf::Error "unknown registration method 'x' (known: ...)" for unknown
// names and the backend registry's error for a bad backend; options are validated.
std::unique_ptr<Registration> make_registration(const std::string& name, const std::string& backend = "cpu");
std::unique_ptr<Registration> make_registration(const std::string& name, const RegistrationOptions& options,
                                                std::unique_ptr<ReductionBackend> backend);
std::vector<std::string> registration_names();  // sorted

}  // namespace hf
