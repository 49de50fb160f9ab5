// "ndt-p2d": point-to-distribution NDT (Magnusson 2007; report section 4.1, eq. 62-66). The reference frame's
// points become the multi-resolution cell model (registration/ndt/ndt_cells.h); the current frame's points are
// scored against the Gaussians of the cell they fall in and its face neighbours, and the score is minimised by
// Newton's method with the analytic gradient and Hessian and a line search, coarse to fine
// (registration/ndt/ndt_newton.h, which also states how degeneracy is judged). Geometry only.
#pragma once

#include "registration/ndt/ndt_options.h"

namespace hf {

RegistrationMethod ndt_p2d_registration_method();

}  // namespace hf
