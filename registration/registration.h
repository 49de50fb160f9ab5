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
  double inlier_ratio = 0.0;   // inliers / rows possible (valid current pixels; photometric rows only on the
                               // finest_level_photometric_step grid), in [0, 1]
  Matrix6d information = Matrix6d::Zero();  // J^T W J at the solution (finest level), xi = (omega, v) order
  // Eigenvalues (ascending) and condition number (largest / smallest; 0 when singular, never inf) of the
  // information with rotations scaled to displacements at the RMS point distance L (S H S, S = diag(1/L x3, 1 x3)),
  // the matrix the degeneracy test uses.
  Vector6d eigenvalues = Vector6d::Zero();
  double condition_number = 0.0;
  int degenerate_dims = 0;     // eigen-directions below the degeneracy threshold (0..6)
  // Unit eigenvector of eigenvalues(0) in the same balanced units, (omega L, v): the direction the data constrain
  // least. Worth a look when eigenvalues(0) / eigenvalues(5) is small but above the degeneracy threshold (a
  // corridor: its axis), where the estimate along it tends to stay near the initial guess.
  Vector6d weakest_direction = Vector6d::Zero();
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
  // Convergence: stop a level when the step is below both (radians, metres). 1e-5 moves a point at 2 m by
  // ~0.005 px at 640x480 and is 50x below the accuracy the tests ask for; a smaller threshold only spends
  // finest-level iterations on rounding-level steps (1e-6 took 2-4 more of them per frame).
  double min_step_rotation_rad = 1e-5;
  double min_step_translation_m = 1e-5;
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
  // Weight lambda of photometric rows in `combined` (eq. 47-48), chosen by a sweep over 0..1 on the real TUM
  // pairs (bench_registration --lambda-sweep; table in bench/results/registration.md): on fr1_rpy (149 pairs)
  // 0.1-0.2 give the lowest mean errors (4.0 mm / 0.35 deg against 5.3 mm / 0.50 deg for lambda 0), fr1_desk
  // (8 pairs) prefers 0.01-0.02 and grows slowly beyond (3.0 mm at 0.1), and 0.2 or more lowers the smallest
  // balanced eigenvalue ratio on real frames to ~2e-3, under the degeneracy threshold. Photometric rows are
  // intensity units ([0, 1]) against metres for ICP, and with finest_level_photometric_step = 2 there are a
  // quarter as many of them at the finest level; lambda was measured with that setting.
  float rgb_weight = 0.1f;
  // Photometric: skip pixels whose reference |grad I| is below this (intensity per pixel; 1/255 = one grey level):
  // they carry no information, and a frame with almost none left is reported as poor (low inlier ratio).
  float min_gradient = 1.0f / 255.0f;
  bool photometric_occlusion_check = true;
  // Photometric rows at the finest level only for every finest_level_photometric_step-th current pixel in x
  // and y (1 = all); geometric rows always use every pixel. The reference images are still sampled at full
  // resolution, so the rows keep level-0 precision while costing a quarter (step 2). Photometric rows are the
  // expensive ones (three bilinear samples each) and neighbouring intensity residuals are strongly correlated,
  // so step 2 loses little; subsampling the ICP rows too (tried) cost combined 0.012 deg on the noise-free room.
  int finest_level_photometric_step = 2;
  // Degeneracy (Zhang et al. 2016): eigen-directions with lambda_i < threshold * lambda_max are not updated.
  // In a direction the geometry leaves free, the balanced ratio lambda_i / lambda_max is set by the normals'
  // noise (~ sigma_n^2), not by the scene: ~2e-4..1.5e-3 for the wall preset at 320x240 with the 7x7 bilateral
  // filter. Well-constrained scenes sit at 1e-2..1.5e-2 (room, holes, textureless; photometric on the room
  // ~1e-2). A corridor lies between (~5e-3 along its axis): weakly, not un-, constrained, and a threshold that
  // flagged it would sit within 1.4x of both the corridor and the room, flipping with the noise level. So the
  // threshold is 3e-3, 2x above the wall's noise floor and 1.7x below the corridor, which is reported good with
  // its weak axis in weakest_direction (tests/registration/test_hard_cases.cpp).
  double degeneracy_threshold = 3e-3;
  // Outcome checks.
  long min_inliers = 64;              // fewer at the finest level: no_data (0 rows) or failed
  double poor_inlier_ratio = 0.3;     // below: poor
  double max_translation_m = 0.5;     // |t| of T_guess^-1 T_result beyond: failed (never a wild pose)
  double max_rotation_deg = 45.0;
  // A result that moved more than verify_motion_m or verify_motion_deg from the initial guess is re-checked by
  // aligning the reference onto the current frame; unless the two agree (the loop T_fwd T_rev is within
  // verify_agreement_m and verify_agreement_deg of the identity) it is reported failed. A large motion is where
  // projective association settles in false minima; 5 cm / 10 deg per frame is above every consecutive pair of
  // TUM fr1 in ../shared/data (hand-held, 30 Hz: at most 1.8 cm (desk) and 6.0 deg (rpy) by their ground truth),
  // so normal tracking never pays for the second alignment.
  double verify_motion_m = 0.05;
  double verify_motion_deg = 10.0;
  double verify_agreement_m = 0.01;
  double verify_agreement_deg = 0.5;
  // The last finest-level step must be below these, else the estimate was still sliding: failed. On real frames
  // the IRLS weights change a little every iteration, so the last step of a converged solve sits near 1e-4 (fr1/rpy
  // at 320x240: 43 of 150 frames ended with steps of 1.4e-4 m / 2e-4 rad, which 2e-4 thresholds rejected as
  // failures); sliding means steps of millimetres and tenths of a degree.
  double max_final_step_translation_m = 2e-3;
  double max_final_step_rotation_rad = 2e-3;

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
