#include "registration/photometric.h"

#include "registration/gauss_newton.h"

namespace hf {

RegistrationOptions photometric_default_options() {
  RegistrationOptions o;
  o.robust_rgb = RobustKernel::student_t;
  // Intensity alignment converges more slowly than point-to-plane ICP (first-order image model): more iterations.
  o.iterations = {20, 10, 10};
  return o;
}

std::unique_ptr<Registration> make_photometric_registration(const RegistrationOptions& options,
                                                            std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>("photometric", HF_REG_PHOTOMETRIC, options, std::move(backend));
}

}  // namespace hf
