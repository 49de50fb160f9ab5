// "photometric": dense photometric alignment (Steinbruecker et al. 2011, Kerl et al. 2013; report section 3.2,
// eq. 27-46), frame to frame on intensity: the current pixels are warped with the current frame's depth into the
// reference intensity image. Per-pixel residual: registration/kernels/photometric_kernel.h. Needs intensity in
// both pyramids (else no_data). Its driver default: 20/10/10 iterations (a first-order image model converges more
// slowly than point-to-plane ICP).
#pragma once

#include "registration/kernels/photometric_kernel.h"
#include "registration/registration.h"

namespace hf {

// The knobs of the photometric term (also combined's photometric term). The measurements behind the defaults:
// bench/results/registration.md ("Method defaults").
struct PhotometricOptions : MethodOptionsBase<PhotometricOptions> {
  // IRLS weights of intensity residuals ([0, 1] units): DVO's Student-t (nu = t_dof) whose sigma photometric alone
  // re-estimates every iteration from t_sigma_rgb_init, floored at t_sigma_rgb_min; or Huber with k = huber_rgb.
  RobustKernel robust_rgb = RobustKernel::student_t;
  float huber_rgb = 0.05f;
  float t_dof = 5.0f;
  float t_sigma_rgb_init = 0.05f;
  float t_sigma_rgb_min = 0.002f;
  // Skip pixels whose reference |grad I| is below this (intensity per pixel; one grey level): they carry no
  // information, and a frame with almost none left is reported poor (low inlier ratio).
  float min_gradient = 1.0f / 255.0f;
  // Reject pixels whose warped depth is more than occlusion_max_depth_m from the reference depth they land on.
  bool photometric_occlusion_check = true;
  float occlusion_max_depth_m = 0.1f;
  // Rows at the finest level only for every step-th current pixel in x and y (1 = all; coarser levels use every
  // pixel); the reference is still sampled at full resolution. 2: a quarter of the cost for little accuracy.
  int finest_level_photometric_step = 2;
  // Exposure: before each level's iterations the current frame's brightness gain against the reference is
  // estimated at the correspondences of the estimate so far (estimate_brightness_gain) and the residual becomes
  // I_ref(w) - gain I_cur, where the gain explains the intensity residual (its median at most
  // brightness_gain_max_ratio of the one under brightness constancy); else constancy (gain 1). Off for photometric
  // alone (not measured there); combined turns it on (registration/combined.h has the measurement).
  bool brightness_gain = false;
  float brightness_gain_max_ratio = 0.1f;

  void visit(OptionVisitor& v) override;
  void validate() const override;
  // The kernel's parameters at pyramid `level` with term weight `weight` and Student-t sigma `t_sigma`.
  hf_photometric_params kernel_params(int level, float weight, float t_sigma) const;
  // The rows it can give at the finest level: valid current pixels on its grid.
  double rows_possible(const FramePyramidLevel& current) const;
};

// The current frame's brightness gain against the reference, I_ref ~ gain I_cur: the ratio of the mean
// intensities at the correspondences of T_ref_cur (current pixels on a step grid warped with their depth, bilinear
// reference samples), once more without the pairs beyond 3 robust standard deviations, clamped to [0.5, 2]. It is
// returned where it explains the residual (median |I_ref - gain I_cur| at most max_ratio of median |I_ref - I_cur|
// over those pairs), else 1; also 1 with fewer than 100 pairs or no intensity.
float estimate_brightness_gain(const FramePyramidLevel& current, const FramePyramidLevel& reference,
                               const hf_transform12& T_ref_cur, float max_ratio, int step = 2);

// The term's kernel (combined reduces it as one of its terms).
const DenseKernel& photometric_kernel();

RegistrationMethod photometric_registration_method();

}  // namespace hf
