// "combined": ICP and photometric rows of the same correspondences stacked with weight lambda
// (Whelan et al. 2013; report section 3.3, eq. 47-48), each term reduced on its own and weighed per direction
// (CombinedOptions::icp_term_threshold; RegistrationResult::terms has both informations). Per-pixel rows: the
// two terms' kernels; registration/kernels/combined_kernel.h is all the rows in one reduction (kernel(), what
// GaussNewtonRegistration::level_problem gives).
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
  // Per-term degeneracy (Zhang et al. 2016 applied to each term): each term is reduced on its own, and its
  // eigen-directions (balanced units, as GaussNewtonOptions::degeneracy_threshold) with eigenvalue at or below
  // this times its largest are projected out of it before the two are added, so a term's weak, noise-biased
  // information (icp along a corridor's axis) does not pull against the term that sees that motion. 0: the plain
  // sum (eq. 47-48). The measurements behind the values: bench/results/registration.md ("combined: per-term
  // degeneracy").
  // 1e-2, chosen on TUM fr1/rpy 0-149 through the pipeline (ATE 1.96 / 1.87 / 2.44 / 2.99 cm at 0 / 1e-2 / 2e-2 /
  // 3e-2: icp's real weak directions carry information the photometric term lacks). The corridor pair would want
  // 3e-2 (9.7 / 3.5 / 1.4 mm at 1e-2 / 2e-2 / 3e-2, photometric alone 1.8 mm; icp's ratios there are 0.005 / 0.020
  // / 0.026 against at least 0.0136 on the room): no single ratio threshold serves both. Report and the other
  // sequences: bench/results/registration.md ("combined: per-term degeneracy").
  double icp_term_threshold = 1e-2;
  double photometric_term_threshold = 0.0;

  CombinedOptions() { photometric.robust_rgb = RobustKernel::huber; }
  void visit(OptionVisitor& v) override;  // icp's keys, photometric's keys, rgb_weight
  void validate() const override;
};

RegistrationMethod combined_registration_method();

}  // namespace hf
