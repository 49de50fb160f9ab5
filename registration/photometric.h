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

  void visit(OptionVisitor& v) override;
  void validate() const override;
  // The kernel's parameters at pyramid `level` with term weight `weight` and Student-t sigma `t_sigma`.
  hf_photometric_params kernel_params(int level, float weight, float t_sigma) const;
  // The rows it can give at the finest level: valid current pixels on its grid.
  double rows_possible(const FramePyramidLevel& current) const;
};

// The term's kernel (combined reduces it as one of its terms).
const DenseKernel& photometric_kernel();

RegistrationMethod photometric_registration_method();

}  // namespace hf
