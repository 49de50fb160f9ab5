#include "registration/sparse.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

RegistrationResult failure(RegistrationStatus status, const SE3& T_initial, std::string message) {
  RegistrationResult r;
  r.T_ref_cur = T_initial;
  r.status = status;
  r.message = std::move(message);
  r.iterations_per_level = {0};
  return r;
}

// The matched features as 3-D pairs with their noise (registration/sparse/rigid_ransac.h).
std::vector<PointPair> point_pairs(const FeatureFrame& current, const FeatureFrame& reference,
                                   const std::vector<FeatureMatch>& matches, double sigma_px) {
  std::vector<PointPair> pairs;
  pairs.reserve(matches.size());
  for (const FeatureMatch& m : matches) {
    const Feature& c = current.features[size_t(m.current)];
    const Feature& r = reference.features[size_t(m.reference)];
    PointPair p;
    p.current = c.point_m;
    p.reference = r.point_m;
    p.Sigma_current = depth_point_covariance(c.point_m, sigma_px * c.scale, current.camera.fx);
    p.Sigma_reference = depth_point_covariance(r.point_m, sigma_px * r.scale, reference.camera.fx);
    pairs.push_back(p);
  }
  return pairs;
}

// S = diag(1/L x3, 1 x3) with L the RMS distance of the current features (balanced_units() for points).
Vector6d feature_units(const FeatureFrame& current) {
  double sum_sq = 0.0;
  for (const Feature& f : current.features) sum_sq += f.point_m.squaredNorm();
  const double L = std::max(1e-3, std::sqrt(sum_sq / double(std::max<size_t>(1, current.features.size()))));
  Vector6d s;
  s << 1.0 / L, 1.0 / L, 1.0 / L, 1.0, 1.0, 1.0;
  return s;
}

class SparseRegistration final : public Registration {
 public:
  bool reads_colour() const override { return true; }  // ORB on the intensity
  explicit SparseRegistration(const RegistrationOptions& options) : options_(options) {
    options_.validate();
    features_ = options_.method_as<SparseOptions>().features;
  }

  RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                           const SE3& T_ref_cur_initial) override {
    const SE3 guess = T_ref_cur_initial.is_finite() ? T_ref_cur_initial : SE3();
    if (!T_ref_cur_initial.is_finite()) {
      return failure(RegistrationStatus::failed, guess, "the initial guess is not finite");
    }
    if (current.num_levels() < 1 || reference.num_levels() < 1) {
      return failure(RegistrationStatus::no_data, guess, "empty pyramid");
    }
    if (!current.has_intensity() || !reference.has_intensity()) {
      return failure(RegistrationStatus::no_data, guess, "sparse needs intensity in both frames");
    }
    try {
      const FeatureFrame cur = extract_features(current.levels[0], features_);
      const FeatureFrame ref = extract_features(reference.levels[0], features_);
      return align_feature_frames(cur, ref, options_, guess);
    } catch (const std::exception& e) {
      return failure(RegistrationStatus::failed, guess, std::string("registration error: ") + e.what());
    }
  }
  std::string name() const override { return "sparse"; }
  const RegistrationOptions& options() const override { return options_; }

 private:
  RegistrationOptions options_;
  FeatureOptions features_;
};

RegistrationOptions sparse_defaults() { return RegistrationOptions(GaussNewtonOptions{}, std::make_unique<SparseOptions>()); }

std::unique_ptr<Registration> make_sparse(const RegistrationOptions& options, std::unique_ptr<ReductionBackend>) {
  return std::make_unique<SparseRegistration>(options);
}

}  // namespace

RegistrationResult align_feature_frames(const FeatureFrame& current, const FeatureFrame& reference,
                                        const RegistrationOptions& options, const SE3& T_initial) {
  const SparseOptions& o = options.method_as<SparseOptions>();
  if (current.empty() || reference.empty()) {
    return failure(RegistrationStatus::no_data, T_initial,
                   std::string("no keypoint with depth in the ") + (current.empty() ? "current" : "reference") +
                       " frame");
  }
  const std::vector<FeatureMatch> matches = match_features(current, reference, o.matching);
  if (int(matches.size()) < o.min_matches) {
    return failure(RegistrationStatus::failed, T_initial,
                   "too few feature matches (" + std::to_string(matches.size()) + " < min_matches " +
                       std::to_string(o.min_matches) + "): textureless or no overlap");
  }
  const std::vector<PointPair> pairs = point_pairs(current, reference, matches, o.keypoint_sigma_px);
  const RigidEstimate est = estimate_rigid_ransac(pairs, o.ransac);
  if (!est.ok || int(est.inliers.size()) < o.min_feature_inliers) {
    RegistrationResult r = failure(RegistrationStatus::failed, T_initial,
                                   "too few RANSAC inliers (" + std::to_string(est.ok ? est.inliers.size() : 0) +
                                       " of " + std::to_string(matches.size()) + " matches, min_feature_inliers " +
                                       std::to_string(o.min_feature_inliers) + ")");
    r.iterations_per_level = {est.hypotheses};
    return r;
  }
  NormalEquations ne;
  ne.JtJ = est.JtJ;
  ne.Jtr = est.Jtr;
  ne.cost = est.cost;
  ne.count = long(est.inliers.size());
  const GaussNewtonStep step = solve_balanced_step(ne, feature_units(current), options.driver.degeneracy_threshold);
  RegistrationResult r;
  r.iterations_per_level = {est.hypotheses};
  if (!step.finite) return failure(RegistrationStatus::failed, T_initial, "non-finite normal equations");
  classify_outcome(options.driver, ne, step, double(matches.size()), T_initial, est.T_ref_cur, est.last_step, r);
  return r;
}

void SparseOptions::visit(OptionVisitor& v) {
  v("max_features", features.max_features);
  v("orb_scale_levels", features.scale_levels);
  v("orb_scale_factor", features.scale_factor);
  v("fast_threshold", features.fast_threshold);
  v("equalize_histogram", features.equalize_histogram);
  v("orb_patch_px", features.patch_px);
  v("depth_edge_sigmas", features.depth_edge_sigmas);
  v("match_ratio", matching.ratio);
  v("cross_check", matching.cross_check);
  v("max_distance_bits", matching.max_distance_bits);
  v("ransac_iterations", ransac.max_iterations);
  v("ransac_confidence", ransac.confidence);
  v("inlier_chi2", ransac.inlier_chi2);
  v("sample_rigidity_sigmas", ransac.sample_rigidity_sigmas);
  v("min_sample_spread_m", ransac.min_sample_spread_m);
  v("refine_iterations", ransac.refine_iterations);
  v("refine_rounds", ransac.refine_rounds);
  long seed = long(ransac.seed);
  v("ransac_seed", seed);
  ransac.seed = std::uint64_t(seed);
  v("keypoint_sigma_px", keypoint_sigma_px);
  v("min_matches", min_matches);
  v("min_feature_inliers", min_feature_inliers);
}

void SparseOptions::validate() const {
  require_option(features.max_features >= 3, "max_features must be >= 3");
  require_option(features.scale_levels >= 1 && features.scale_levels <= 16, "orb_scale_levels must be in 1..16");
  require_option(std::isfinite(features.scale_factor) && features.scale_factor > 1.0f && features.scale_factor <= 2.0f,
                 "orb_scale_factor must be in (1, 2]");
  require_option(features.fast_threshold >= 1 && features.fast_threshold <= 254, "fast_threshold must be in 1..254");
  require_option(features.patch_px >= 5 && features.patch_px <= 63, "orb_patch_px must be in 5..63");
  require_option(finite_positive(features.depth_edge_sigmas), "depth_edge_sigmas must be finite and > 0");
  require_option(std::isfinite(matching.ratio) && matching.ratio > 0.0f && matching.ratio <= 1.0f,
                 "match_ratio must be in (0, 1]");
  require_option(matching.max_distance_bits >= 0 && matching.max_distance_bits <= 256,
                 "max_distance_bits must be in 0..256");
  require_option(ransac.max_iterations >= 1, "ransac_iterations must be >= 1");
  require_option(ransac.confidence > 0.0 && ransac.confidence < 1.0, "ransac_confidence must be in (0, 1)");
  require_option(finite_positive(ransac.inlier_chi2), "inlier_chi2 must be finite and > 0");
  require_option(finite_positive(ransac.sample_rigidity_sigmas), "sample_rigidity_sigmas must be finite and > 0");
  require_option(std::isfinite(ransac.min_sample_spread_m) && ransac.min_sample_spread_m >= 0.0,
                 "min_sample_spread_m must be finite and >= 0");
  require_option(ransac.refine_iterations >= 1, "refine_iterations must be >= 1");
  require_option(ransac.refine_rounds >= 1, "refine_rounds must be >= 1");
  require_option(finite_positive(keypoint_sigma_px), "keypoint_sigma_px must be finite and > 0");
  require_option(min_matches >= 3, "min_matches must be >= 3");
  require_option(min_feature_inliers >= 3, "min_feature_inliers must be >= 3");
}

RegistrationMethod sparse_registration_method() { return {"sparse", sparse_defaults, make_sparse}; }

}  // namespace hf
