// "ndt-d2d": distribution-to-distribution NDT (Stoyanov et al. 2012; report section 4.3, eq. 71-75). Both frames
// become multi-resolution cell models; each current Gaussian N(mu_i, Sigma_i), moved by T, is scored against the
// reference Gaussians of the cell its mean falls in and that cell's face neighbours with
// s = d1 exp(-d2/2 x'^T (R Sigma_i R^T + Sigma_j)^-1 x'), x' = T mu_i - mu_j (eq. 74-75), by the Newton solver of
// registration/ndt/ndt_newton.h. The combined covariance is evaluated at each iteration's rotation and held fixed
// within it (its derivative with respect to the rotation is left out, as GICP does), so the Hessian is the
// point-to-distribution one of the moved means. Geometry only.
#pragma once

#include "registration/ndt/ndt_options.h"

namespace hf {

RegistrationMethod ndt_d2d_registration_method();

}  // namespace hf
