// "icp": KinectFusion point-to-plane ICP with projective data association (report section 3.1, eq. 12-26).
// Per-pixel residual: registration/kernels/icp_kernel.h. Works on geometry only (no intensity needed).
// Defaults: Huber weights with k = 1 cm on the point-to-plane distance, 10 cm / 30 degree rejection gates.
#pragma once

#include <memory>

#include "registration/registration.h"

namespace hf {

RegistrationOptions icp_default_options();
std::unique_ptr<Registration> make_icp_registration(const RegistrationOptions& options,
                                                    std::unique_ptr<ReductionBackend> backend);

}  // namespace hf
