// "icp": KinectFusion point-to-plane ICP with projective data association (report section 3.1, eq. 12-26).
// Per-pixel residual: registration/kernels/icp_kernel.h. Works on geometry only (no intensity needed).
#pragma once

#include "registration/kernels/icp_kernel.h"
#include "registration/registration.h"

namespace hf {

// The knobs of the point-to-plane term (also combined's geometric term). The measurements behind the defaults:
// bench/results/registration.md ("Method defaults").
struct IcpOptions : MethodOptionsBase<IcpOptions> {
  // Correspondence rejection, the same gate on every level (KinectFusion: 10 cm, 30 degrees; a wider coarse gate
  // pulls the fast preset into wrong minima).
  float max_dist_m = 0.1f;
  float max_normal_angle_deg = 30.0f;
  // IRLS weights of the point-to-plane distance (metres): Huber with k = 1 cm, or Student-t with a fixed sigma.
  RobustKernel robust_icp = RobustKernel::huber;
  float huber_icp_m = 0.01f;
  float t_sigma_icp_m = 0.01f;
  float t_dof_icp = 5.0f;  // nu
  // Rows weighed by the depth sensor's noise beyond depth_noise_ref_m (hf_icp_depth_scale, icp_kernel.h): a point
  // measured at depth z > ref counts (ref / z)^4 of a nearer one and the robust kernel sees its residual scaled by
  // (ref / z)^2, as sigma_z ~ z^2 (Nguyen et al. 2012; disparity steps). 0: every row alike (KinectFusion), the
  // default. Measured through the pipeline in combined (bench/results/registration.md, "combined: icp's rows
  // weighed by the depth noise"), chosen on the corridor (seed 1) and TUM fr1/rpy 0-149: 2.5 m takes the corridor
  // 14.3 -> 5.3 mm (its far walls' grazing, quantised points are where icp's biased weak-direction information comes
  // from; photometric alone 1.7 mm) and TUM 0-149 1.87 -> 1.79 cm; reported: corridor seeds 0 / 2 / 3 14.3 / 13.9
  // / 13.9 -> 5.7 / 5.7 / 5.2 mm, TUM fr1/rpy 150-269 1.71 -> 1.84 cm, 7-Scenes 2.60 -> 2.62 cm, fr1/desk 0.245 cm
  // (same), the other presets the same or better but unregistered (5.2 -> 6.2 mm). Off by default: worse on two
  // real sequences and short of issue 16's corridor target (1.5x photometric, 2.5 mm).
  float depth_noise_ref_m = 0.0f;

  void visit(OptionVisitor& v) override;
  void validate() const override;
  // The kernel's parameters with term weight `weight`.
  hf_icp_params kernel_params(float weight = 1.0f) const;
};

// The term's kernel (combined reduces it as one of its terms).
const DenseKernel& icp_kernel();

RegistrationMethod icp_registration_method();

}  // namespace hf
