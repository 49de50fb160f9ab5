#include "registration/combined.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <deque>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/combined_kernel.h"
#include "registration/so3_prealign.h"

namespace hf {
namespace {

constexpr unsigned kCombinedInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_NORMALS) |
                             HF_REG_IN_BIT(HF_REG_IN_CUR_INTENSITY) | HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_NORMALS) | HF_REG_IN_BIT(HF_REG_IN_REF_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_X) | HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_Y);
const DenseKernel kCombinedKernel = make_dense_kernel<hf_combined_params, hf_combined_pixel>(
    "combined", kCombinedInputs, 2, &detail::combined_rows_avx2);

// One term in the balanced units S (rotations as displacements at the RMS point distance, as the driver's
// degeneracy test): Hs = S H S, gs = S g, the projector P onto its eigen-directions with eigenvalue above
// threshold times its largest (Zhang et al. 2016, per term; the identity for threshold 0) and that largest.
struct BalancedTerm {
  Matrix6d H, P;
  Vector6d g;
  double lmax = 0.0;
};

bool balance(const NormalEquations& term, const Vector6d& unit_scale, double threshold, const Matrix6d& keep,
             BalancedTerm* out) {
  out->H = keep * (unit_scale.asDiagonal() * term.JtJ * unit_scale.asDiagonal()) * keep;
  out->g = keep * unit_scale.cwiseProduct(term.Jtr);
  out->P = Matrix6d::Identity();
  if (!out->H.allFinite() || !out->g.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(out->H);
  if (eig.info() != Eigen::Success) return false;
  out->lmax = std::max(0.0, eig.eigenvalues()(5));
  if (!(threshold > 0.0)) return true;
  out->P.setZero();
  for (int i = 0; i < 6; ++i) {
    if (out->lmax > 0.0 && eig.eigenvalues()(i) > threshold * out->lmax)
      out->P += eig.eigenvectors().col(i) * eig.eigenvectors().col(i).transpose();
  }
  return true;
}

// The two terms with each one's degenerate directions projected out: H = P_i H_i P_i + Q P_p H_p P_p Q,
// g = P_i g_i + Q P_p g_p (balanced units, mapped back). Along the directions icp leaves (I - P_i) the
// photometric term is weighed up to icp's scale, Q = P_i + s (I - P_i) with s^2 = max(1, lmax_i / lmax_p), so the
// driver's degeneracy test judges it there by its own eigenvalue ratio, not against icp's largest eigenvalue
// (which lambda = rgb_weight would make arbitrary). s moves neither the solution (g = 0 needs P_i (g_i + g_p) = 0
// and (I - P_i) g_p = 0 for any s > 0) nor anything where icp is well constrained (Q = I there).
NormalEquations combine_per_direction(const NormalEquations& icp, const NormalEquations& photometric,
                                      const Vector6d& unit_scale, double icp_threshold, double photometric_threshold,
                                      const Matrix6d& icp_keep) {
  NormalEquations out;
  out.cost = icp.cost + photometric.cost;
  out.count = icp.count + photometric.count;
  BalancedTerm i, p;
  if (!balance(icp, unit_scale, icp_threshold, icp_keep, &i) ||
      !balance(photometric, unit_scale, photometric_threshold, Matrix6d::Identity(), &p)) {
    out.JtJ = icp.JtJ + photometric.JtJ;  // non-finite: the driver reports it
    out.Jtr = icp.Jtr + photometric.Jtr;
    return out;
  }
  const double s = p.lmax > 0.0 ? std::sqrt(std::max(1.0, i.lmax / p.lmax)) : 1.0;
  const Matrix6d Q = i.P + s * (Matrix6d::Identity() - i.P);
  const Matrix6d Hp = p.P * p.H * p.P;
  Matrix6d H = i.P * i.H * i.P + Q * Hp * Q;
  H = 0.5 * (H + H.transpose());
  const Vector6d g = i.P * i.g + Q * (p.P * p.g);
  const Vector6d inv_scale = unit_scale.cwiseInverse();
  out.JtJ = inv_scale.asDiagonal() * H * inv_scale.asDiagonal();
  out.Jtr = inv_scale.cwiseProduct(g);
  return out;
}

}  // namespace

// icp's weak eigen-directions (balanced units, eigenvalue at or below icp_probe_ratio of its largest) checked
// against the cost: the icp term is reduced again at the estimate moved by +-icp_probe_step_m along each, its
// correspondences found anew, and the cost's second difference (per row, so rows entering or leaving at the edges
// do not count) is compared with what the normal equations claim, c(+d) + c(-d) - 2 c(0) = 2 d^2 lambda. Along a
// corridor's axis the point-to-plane residuals do not change when the camera slides (every point meets the same
// walls again), so the information there comes from the normals' noise and the residuals' noise, not from the
// geometry: the cost stays flat while lambda says otherwise. Such a direction (observed / claimed below
// icp_probe_min_ratio) is left out of icp's term where the photometric term constrains it (its information along
// it at least icp_probe_photometric_ratio of its largest). The result: the projector onto the directions kept.
Matrix6d icp_observed_directions(const NormalEquations& icp, const NormalEquations& photometric,
                                 const Vector6d& unit_scale, const CombinedOptions& o,
                                 const DenseMethod::TermProbe& reduce_at, std::vector<IcpDirectionProbe>* probes) {
  Matrix6d keep = Matrix6d::Identity();
  if (probes) probes->clear();
  if (!(o.icp_probe_ratio > 0.0) || icp.count < 6) return keep;
  const Matrix6d H = unit_scale.asDiagonal() * icp.JtJ * unit_scale.asDiagonal();
  const Matrix6d Hp = unit_scale.asDiagonal() * photometric.JtJ * unit_scale.asDiagonal();
  if (!H.allFinite() || !Hp.allFinite() || !std::isfinite(icp.cost)) return keep;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(H);
  if (eig.info() != Eigen::Success) return keep;
  const double lmax = eig.eigenvalues()(5);
  if (!(lmax > 0.0)) return keep;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig_p(Hp, Eigen::EigenvaluesOnly);
  const double lp = eig_p.info() == Eigen::Success ? eig_p.eigenvalues()(5) : 0.0;
  const double c0 = icp.cost / double(icp.count);
  const double d = o.icp_probe_step_m;
  for (int k = 0; k < 5; ++k) {
    const double lambda = eig.eigenvalues()(k);
    if (lambda > o.icp_probe_ratio * lmax) break;  // ascending: the rest are stronger
    const Vector6d v = eig.eigenvectors().col(k);
    const NormalEquations plus = reduce_at(0, d * unit_scale.cwiseProduct(v));
    const NormalEquations minus = reduce_at(0, -d * unit_scale.cwiseProduct(v));
    if (plus.count < 6 || minus.count < 6 || !std::isfinite(plus.cost) || !std::isfinite(minus.cost)) continue;
    // Per-row costs times the rows at the estimate: the second difference of the cost at a fixed row count.
    const double second = (plus.cost / double(plus.count) + minus.cost / double(minus.count) - 2.0 * c0) *
                          double(icp.count);
    const double claimed = 2.0 * d * d * std::max(lambda, 0.0);
    const double observed_ratio = claimed > 0.0 ? second / claimed : 0.0;
    // Left out only where the photometric term sees that direction itself: else icp's little is all there is.
    const double photometric_ratio = lp > 0.0 ? v.dot(Hp * v) / lp : 0.0;
    const bool kept = observed_ratio >= o.icp_probe_min_ratio || photometric_ratio < o.icp_probe_photometric_ratio;
    if (!kept) keep -= v * v.transpose();
    if (probes) probes->push_back({v, lambda / lmax, observed_ratio, photometric_ratio, kept});
  }
  return keep;
}

namespace {

class CombinedMethod final : public DenseMethod {
 public:
  explicit CombinedMethod(const CombinedOptions& options) : options_(options) {}
  const DenseKernel& kernel() const override { return kCombinedKernel; }
  void begin_level(int level, const FramePyramidLevel& current, const FramePyramidLevel& reference,
                   ResidualProblem& problem) override {
    // A registration's first level follows the previous one's finest: its scale joins the sequence's.
    if (level_ == 0 && frame_scale_ > 0.0) record_scale(frame_scale_);
    frame_scale_ = 0.0;
    level_ = level;
    photometric_ = options_.photometric;
    float rgb_weight = options_.rgb_weight;
    if (clean_) {
      photometric_.t_dof = options_.clean_t_dof;
      photometric_.t_sigma_rgb_min = options_.clean_t_sigma_rgb_min;
      rgb_weight *= options_.clean_rgb_weight_gain;
    }
    params_.icp = options_.icp.kernel_params();
    params_.photometric = photometric_.kernel_params(level, rgb_weight, photometric_.t_sigma_rgb_init);
    if (options_.photometric.brightness_gain) {
      params_.photometric.gain = estimate_brightness_gain(current, reference, problem.T_ref_cur,
                                                          options_.photometric.brightness_gain_max_ratio);
    }
  }
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices)) + options_.photometric.rows_possible(current);
  }
  std::vector<std::string> term_names() const override { return {"icp", "photometric"}; }
  ResidualProblem term_problem(int t, const ResidualProblem& level) const override {
    ResidualProblem p = level;
    p.kernel = t == 0 ? &icp_kernel() : &photometric_kernel();
    p.params = t == 0 ? static_cast<const void*>(&params_.icp) : static_cast<const void*>(&params_.photometric);
    p.pixel_step = t == 0 ? 1 : std::max(1, params_.photometric.step);
    return p;
  }
  NormalEquations combine_terms(const std::vector<NormalEquations>& terms, const Vector6d& unit_scale) const override {
    photometric_cost_ = terms[1].cost;
    photometric_rows_ = terms[1].count;
    return combine_per_direction(terms[0], terms[1], unit_scale, options_.icp_term_threshold,
                                 options_.photometric_term_threshold, icp_keep_);
  }
  // DVO's scale of the photometric term, as photometric alone re-estimates it (photometric.cpp), from the term's
  // own rows: their cost is lambda sum w r^2, so sigma^2 = cost / (lambda n). Reduced apart from icp's rows, the
  // term's scale no longer mixes metres and intensities.
  // The finest level's last estimate is the frame's scale (CombinedOptions::clean_scale_rgb).
  void end_iteration(const NormalEquations&) override {
    const float lambda = params_.photometric.weight;
    if (photometric_.robust_rgb != RobustKernel::student_t || photometric_rows_ <= 0 || !(lambda > 0.0f)) return;
    const double sigma2 = photometric_cost_ / (double(lambda) * double(photometric_rows_));
    if (!std::isfinite(sigma2) || !(sigma2 >= 0.0)) return;
    params_.photometric.robust.scale = std::max(photometric_.t_sigma_rgb_min, float(std::sqrt(sigma2)));
    if (level_ == 0) frame_scale_ = std::sqrt(sigma2);
  }
  void probe_terms(const std::vector<NormalEquations>& terms, const Vector6d& unit_scale,
                   const TermProbe& reduce_at) override {
    icp_keep_ = icp_observed_directions(terms[0], terms[1], unit_scale, options_, reduce_at, nullptr);
  }

 private:
  CombinedOptions options_;
  hf_combined_params params_{};
  // The photometric term's own cost and rows of the last reduction (combine_terms is the one place the driver
  // hands over the terms; end_iteration re-estimates the term's scale from them).
  mutable double photometric_cost_ = 0.0;
  mutable long photometric_rows_ = 0;
  Matrix6d icp_keep_ = Matrix6d::Identity();
  // The photometric regime (CombinedOptions::clean_scale_rgb): the options of the level begun last (level_), the
  // scales of the last registrations' finest levels (oldest first), the regime they make (decided once per
  // registration, when its first level records the previous one's scale) and this registration's scale so far.
  PhotometricOptions photometric_;
  std::deque<double> scale_history_;
  bool clean_ = false;
  double frame_scale_ = 0.0;
  int level_ = -1;

  void record_scale(double scale) {
    scale_history_.push_back(scale);
    while (int(scale_history_.size()) > options_.scale_history) scale_history_.pop_front();
    clean_ = options_.sequence_is_clean(scale_history_);
  }
};

// align()'s defaults widen the basin for a pair without a motion prior (issue 34: 12 degrees and 10 cm between
// frames): two coarser levels (5 from 640x480, the coarsest 40x30) and the rotation-first step on the two coarsest.
// Chosen on TUM fr1/rpy 0-149 pairs, reported on 150-269 (bench/results/accuracy/large_motion.md, "align()'s
// defaults"). The pipeline tracks from a motion prior at its own depth without them
// (slam::pipeline_registration_options).
RegistrationOptions combined_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {10, 5, 4, 4, 4};
  driver.so3_iterations = wide_basin_so3_iterations();
  return RegistrationOptions(driver, std::make_unique<CombinedOptions>());
}

std::unique_ptr<Registration> make_combined(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "combined", std::make_unique<CombinedMethod>(options.method_as<CombinedOptions>()), options, std::move(backend));
}

}  // namespace

void CombinedOptions::visit(OptionVisitor& v) {
  icp.visit(v);
  photometric.visit(v);
  v("rgb_weight", rgb_weight);
  v("icp_term_threshold", icp_term_threshold);
  v("photometric_term_threshold", photometric_term_threshold);
  v("icp_probe_ratio", icp_probe_ratio);
  v("icp_probe_step_m", icp_probe_step_m);
  v("icp_probe_min_ratio", icp_probe_min_ratio);
  v("icp_probe_photometric_ratio", icp_probe_photometric_ratio);
  v("clean_scale_rgb", clean_scale_rgb);
  v("scale_history", scale_history);
  v("scale_history_min", scale_history_min);
  v("clean_t_dof", clean_t_dof);
  v("clean_t_sigma_rgb_min", clean_t_sigma_rgb_min);
  v("clean_rgb_weight_gain", clean_rgb_weight_gain);
}

bool CombinedOptions::sequence_is_clean(const std::deque<double>& scales) const {
  if (!(clean_scale_rgb > 0.0f) || photometric.robust_rgb != RobustKernel::student_t ||
      int(scales.size()) < std::max(1, scale_history_min))
    return false;
  std::vector<double> s(scales.begin(), scales.end());
  const auto mid = s.begin() + std::ptrdiff_t(s.size() / 2);
  std::nth_element(s.begin(), mid, s.end());
  return *mid < double(clean_scale_rgb);
}

void CombinedOptions::validate() const {
  icp.validate();
  photometric.validate();
  require_option(std::isfinite(rgb_weight) && rgb_weight >= 0.0f, "rgb_weight must be finite and >= 0");
  require_option(std::isfinite(icp_term_threshold) && icp_term_threshold >= 0.0 && icp_term_threshold < 1.0,
                 "icp_term_threshold must be in [0, 1)");
  require_option(std::isfinite(photometric_term_threshold) && photometric_term_threshold >= 0.0 &&
                     photometric_term_threshold < 1.0,
                 "photometric_term_threshold must be in [0, 1)");
  require_option(std::isfinite(icp_probe_ratio) && icp_probe_ratio >= 0.0 && icp_probe_ratio < 1.0,
                 "icp_probe_ratio must be in [0, 1)");
  require_option(std::isfinite(icp_probe_step_m) && icp_probe_step_m > 0.0, "icp_probe_step_m must be > 0");
  require_option(std::isfinite(icp_probe_min_ratio) && icp_probe_min_ratio >= 0.0,
                 "icp_probe_min_ratio must be >= 0");
  require_option(std::isfinite(icp_probe_photometric_ratio) && icp_probe_photometric_ratio >= 0.0 &&
                     icp_probe_photometric_ratio <= 1.0,
                 "icp_probe_photometric_ratio must be in [0, 1]");
  require_option(std::isfinite(clean_scale_rgb) && clean_scale_rgb >= 0.0f, "clean_scale_rgb must be finite and >= 0");
  require_option(scale_history >= 1 && scale_history <= 1000, "scale_history must be in [1, 1000]");
  require_option(scale_history_min >= 1 && scale_history_min <= scale_history,
                 "scale_history_min must be in [1, scale_history]");
  require_option(finite_positive(clean_t_dof), "clean_t_dof must be finite and > 0");
  require_option(finite_positive(clean_t_sigma_rgb_min), "clean_t_sigma_rgb_min must be finite and > 0");
  require_option(std::isfinite(clean_rgb_weight_gain) && clean_rgb_weight_gain >= 0.0f,
                 "clean_rgb_weight_gain must be finite and >= 0");
}

RegistrationMethod combined_registration_method() { return {"combined", combined_defaults, make_combined}; }

}  // namespace hf
