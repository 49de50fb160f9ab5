// "sparse": feature-based registration (Endres et al. 2012; Huang et al. 2011; report section 5): ORB keypoints
// with depth in both frames (registration/sparse/feature_matcher.h), matched by Hamming distance with a ratio test
// and a cross-check, RANSAC over 3-point rigid fits with the inlier test from the depth noise model, then a
// Mahalanobis least-squares refinement on the inliers (registration/sparse/rigid_ransac.h).
//
// Why it exists: the wide baseline. Its answer does not depend on the initial guess (no convergence basin), so it
// tracks motions no dense method reaches (the `fast` preset: 15 degrees and 10 cm between frames); its accuracy is
// that of keypoint localisation. A dense method started from its estimate refines it (slam::PipelineConfig
// seed_registration).
//
// Reads level 0 of both pyramids only (intensity and vertices). Outcome, by the driver's public rules
// (registration/gauss_newton.h: solve_balanced_step, classify_outcome): inliers = RANSAC inliers, inlier_ratio =
// inliers / matches, information = J^T C^-1 J of the 3-D residuals at the solution (xi = (omega, v)); no_data when
// either frame has no intensity or no keypoint with depth, failed when there are fewer than min_matches matches
// (textureless) or fewer than min_feature_inliers inliers: a status, never a guess. The reverse alignment of large
// motions (verify_large_motion) is not run: RANSAC's consensus does not settle in a basin around the guess.
#pragma once

#include "registration/registration.h"
#include "registration/sparse/feature_matcher.h"
#include "registration/sparse/rigid_ransac.h"

namespace hf {

struct SparseOptions : MethodOptionsBase<SparseOptions> {
  FeatureOptions features;
  MatchOptions matching;
  RansacOptions ransac;
  // Localisation sigma of a keypoint at ORB octave 0 (pixels of the level), scaled by the octave's scale: FAST
  // corners on the integer grid (sub-pixel sigma ~0.3 px) blurred by the detector's window.
  double keypoint_sigma_px = 1.0;
  int min_matches = 12;          // fewer matches after the ratio test and cross-check: failed (textureless)
  // Fewer RANSAC inliers: failed. The textureless room gives 13-17 (shading edges; flagged degenerate in one
  // direction), the `fast` preset 50-110, a TUM fr1 pair 100+.
  int min_feature_inliers = 20;

  void visit(OptionVisitor& v) override;
  void validate() const override;
};

// Aligns two frames' features (extracted with options' FeatureOptions) by the rules above: the estimate, inliers,
// information and status of a RegistrationResult (degeneracy judged with rotations scaled by the RMS distance of
// the current features' points, as balanced_units() does for pixels). T_initial only bounds the motion
// (max_translation_m / max_rotation_deg of options.driver) and is the answer of a failure. Never throws, except
// hf::Error when options do not hold SparseOptions.
RegistrationResult align_feature_frames(const FeatureFrame& current, const FeatureFrame& reference,
                                        const RegistrationOptions& options, const SE3& T_initial = SE3());

RegistrationMethod sparse_registration_method();

}  // namespace hf
