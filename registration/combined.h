// "combined": ICP and photometric rows of the same correspondences stacked with weight lambda
// (Whelan et al. 2013; report section 3.3, eq. 47-48). Per-pixel residual: registration/kernels/combined_kernel.h.
// Defaults: Huber weights on both terms (the photometric scale cannot be re-estimated from a cost that mixes
// metres and intensities), lambda = rgb_weight.
#pragma once

#include "registration/icp.h"
#include "registration/photometric.h"

namespace hf {

struct CombinedOptions : MethodOptionsBase<CombinedOptions> {
  IcpOptions icp;
  PhotometricOptions photometric;  // its robust_rgb defaults to Huber here
  // lambda of eq. 47-48, the weight of the photometric rows (intensity units against ICP's metres): the optimum of
  // the frame-to-frame sweep on TUM fr1 (bench/results/registration.md, "Choice of lambda").
  float rgb_weight = 0.1f;

  CombinedOptions() { photometric.robust_rgb = RobustKernel::huber; }
  void visit(OptionVisitor& v) override;  // icp's keys, photometric's keys, rgb_weight
  void validate() const override;
};

RegistrationMethod combined_registration_method();

}  // namespace hf
