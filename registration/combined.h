// "combined": ICP and photometric rows of the same correspondences stacked with weight lambda
// (Whelan et al. 2013; report section 3.3, eq. 47-48), each term reduced on its own and weighed per direction
// (CombinedOptions::icp_term_threshold; RegistrationResult::terms has both informations). Per-pixel rows: the
// two terms' kernels; registration/kernels/combined_kernel.h is all the rows in one reduction (kernel(), what
// GaussNewtonRegistration::level_problem gives).
// Defaults: Huber weights on icp's term, Student-t on the photometric term (nu 10, its sigma re-estimated from the
// term's own rows each iteration and floored at 0.02), icp's rows weighed by the depth noise beyond 2.5 m
// (IcpOptions::depth_noise_ref_m), lambda = rgb_weight; in a sequence whose photometric scale is below 0.009 (its
// images agree with the model to about two grey levels: clean_scale_rgb below) the photometric term at its own
// scale instead (nu 3, floor 0.002, lambda x 5). Chosen on the corridor preset (seed 1) and TUM fr1/rpy 0-149
// (bench/results/registration.md, "combined: icp's rows weighed by the depth noise", "combined's new defaults" and
// "combined: two photometric regimes"): corridor 14.3 -> 5.4 -> 2.3 mm (photometric alone 1.7), TUM 0-149 1.87 ->
// 1.85 cm; reported on fr1/desk 0.245 -> 0.224 cm, 7-Scenes 2.60 -> 2.58 cm, TUM 150-269 1.71 -> 1.69 cm (seen
// while choosing the first two) and every other preset (the regimes: room, wall and textureless seen; wall 0.41 ->
// 2.33 mm against icp's 2.27, the price of the corridor).
#pragma once

#include <deque>

#include "registration/dense_method.h"
#include "registration/icp.h"
#include "registration/photometric.h"

namespace hf {

struct CombinedOptions : MethodOptionsBase<CombinedOptions> {
  IcpOptions icp;
  PhotometricOptions photometric;  // here: Student-t, nu 10, sigma floor 0.02 (see above)
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
  // The observed-information check of icp's weak directions (icp_observed_directions below), once per pyramid
  // level: icp's eigen-directions at or below icp_probe_ratio of its largest are probed at +-icp_probe_step_m
  // (balanced metres) and left out of icp's term where the cost's curvature is below icp_probe_min_ratio of the
  // one its normal equations claim and the photometric term's information along them is at least
  // icp_probe_photometric_ratio of its largest. 0: no check (the default). Measured (bench/results/registration.md,
  // "combined: observed information, brightness gain"), ratio 0.05 / 5 mm / 0.5: corridor sequence 14.3 -> 9.6 mm
  // (photometric 1.7 mm), TUM fr1/rpy 0-149 1.87 -> 2.39 cm without the photometric test, 1.89 cm with it at 0.05
  // (0.07: 1.91 cm; 0.1 leaves nothing out on the corridor). TUM's weak directions show 0.1-0.9 of their claimed
  // curvature through the model raycast, the corridor's axis -0.5-0.06: the classes overlap, so it is off by
  // default. The corridor pair (frame to frame): 9.7 -> 1.8 mm, photometric 1.8 mm.
  double icp_probe_ratio = 0.0;
  double icp_probe_step_m = 0.005;
  double icp_probe_min_ratio = 0.5;
  double icp_probe_photometric_ratio = 0.05;

  // Exposure: the photometric term's brightness gain (PhotometricOptions::brightness_gain) is on here: exposure
  // sequence 1.98 -> 0.73 mm (icp 1.00 mm), TUM fr1/rpy 0-149 1.870 -> 1.872 cm with max_ratio 0.1, where without
  // the max_ratio test (every estimated gain used) TUM gets 2.11 cm. Chosen there, reported on the rest:
  // bench/results/registration.md ("combined: observed information, brightness gain").
  // Two photometric regimes, told apart by the sequence's own photometric scale: the median, over the last
  // scale_history registrations (at least scale_history_min of them; fewer: the default regime), of the Student-t
  // scale the finest level ends with. Below clean_scale_rgb (intensity in [0, 1]: 2.3 grey levels) the images agree
  // with the model almost exactly (little sensor noise, no blur, no rolling shutter), so the few large residuals
  // are outliers (the corridor's far, barely fused walls) and the photometric term is trusted at its own scale:
  // nu clean_t_dof, floor clean_t_sigma_rgb_min, rgb_weight times clean_rgb_weight_gain. Otherwise the options
  // above, where large residuals carry motion blur and rolling shutter and a floor of 0.02 keeps them. Measured
  // scales (finest level, 640x480 tracked at 320x240): the real sequences' running medians 0.0095 (7-Scenes' first
  // five frames) to 0.07, never below 0.0131 after their first ten frames; the synthetic presets' 0.005-0.0079.
  // 0: one regime. Chosen on the corridor (seed 1) with room, wall and textureless seen (bench/results/
  // registration.md, "combined: two photometric regimes"): corridor 5.0 -> 2.3 mm; the real sequences stay in the
  // default regime throughout (identical trajectories).
  float clean_scale_rgb = 0.009f;
  int scale_history = 15;
  int scale_history_min = 5;
  float clean_t_dof = 3.0f;
  float clean_t_sigma_rgb_min = 0.002f;
  float clean_rgb_weight_gain = 5.0f;
  // Whether `scales` (the finest levels' Student-t scales, oldest first) make the sequence clean, as above.
  bool sequence_is_clean(const std::deque<double>& scales) const;

  CombinedOptions() {
    photometric.robust_rgb = RobustKernel::student_t;
    photometric.t_dof = 10.0f;
    photometric.t_sigma_rgb_min = 0.02f;
    photometric.brightness_gain = true;
    icp.depth_noise_ref_m = 2.5f;
  }
  void visit(OptionVisitor& v) override;  // icp's keys, photometric's keys, rgb_weight
  void validate() const override;
};

// One probed direction of icp_observed_directions (balanced units), for tests and diagnostics.
struct IcpDirectionProbe {
  Vector6d direction;
  double eigen_ratio = 0.0;     // its eigenvalue over icp's largest
  double observed_ratio = 0.0;     // the cost's second difference over the one the normal equations claim
  double photometric_ratio = 0.0;  // the photometric term's information along it over its largest
  bool kept = true;
};
Matrix6d icp_observed_directions(const NormalEquations& icp, const NormalEquations& photometric,
                                 const Vector6d& unit_scale, const CombinedOptions& o,
                                 const DenseMethod::TermProbe& reduce_at, std::vector<IcpDirectionProbe>* probes);

RegistrationMethod combined_registration_method();

}  // namespace hf
