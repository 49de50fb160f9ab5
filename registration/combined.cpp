#include "registration/combined.h"

#include "registration/gauss_newton.h"

namespace hf {

RegistrationOptions combined_default_options() {
  RegistrationOptions o;
  o.robust_icp = RobustKernel::huber;
  o.robust_rgb = RobustKernel::huber;
  return o;
}

std::unique_ptr<Registration> make_combined_registration(const RegistrationOptions& options,
                                                         std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>("combined", HF_REG_COMBINED, options, std::move(backend));
}

}  // namespace hf
