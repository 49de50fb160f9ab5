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

  void visit(OptionVisitor& v) override;
  void validate() const override;
  // The kernel's parameters with term weight `weight`.
  hf_icp_params kernel_params(float weight = 1.0f) const;
};

// The term's kernel (combined reduces it as one of its terms).
const DenseKernel& icp_kernel();

RegistrationMethod icp_registration_method();

}  // namespace hf
