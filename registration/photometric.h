// "photometric": dense photometric alignment (Steinbruecker et al. 2011, Kerl et al. 2013; report section 3.2,
// eq. 27-46), frame to frame on intensity: the current pixels are warped with the current frame's depth into the
// reference intensity image. Per-pixel residual: registration/kernels/photometric_kernel.h.
// Defaults: DVO's Student-t weights (nu = 5, sigma re-estimated every iteration), occlusion check against the
// reference depth. Needs intensity in both pyramids (else no_data).
#pragma once

#include <memory>

#include "registration/registration.h"

namespace hf {

RegistrationOptions photometric_default_options();
std::unique_ptr<Registration> make_photometric_registration(const RegistrationOptions& options,
                                                            std::unique_ptr<ReductionBackend> backend);

}  // namespace hf
