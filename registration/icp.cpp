#include "registration/icp.h"

#include "registration/gauss_newton.h"

namespace hf {

RegistrationOptions icp_default_options() {
  RegistrationOptions o;
  o.robust_icp = RobustKernel::huber;
  return o;
}

std::unique_ptr<Registration> make_icp_registration(const RegistrationOptions& options,
                                                    std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>("icp", HF_REG_ICP, options, std::move(backend));
}

}  // namespace hf
