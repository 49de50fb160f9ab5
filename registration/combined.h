// "combined": ICP and photometric rows of the same correspondences stacked with weight lambda
// (Whelan et al. 2013; report section 3.3, eq. 47-48). Per-pixel residual: registration/kernels/residuals.h.
// Defaults: Huber weights on both terms (the photometric scale cannot be re-estimated from a cost that mixes
// metres and intensities), lambda = RegistrationOptions::rgb_weight chosen on TUM fr1 (bench/results).
#pragma once

#include <memory>

#include "registration/registration.h"

namespace hf {

RegistrationOptions combined_default_options();
std::unique_ptr<Registration> make_combined_registration(const RegistrationOptions& options,
                                                         std::unique_ptr<ReductionBackend> backend);

}  // namespace hf
