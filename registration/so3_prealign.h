// Rotation-first alignment (ElasticFusion's SO(3) pre-alignment, Whelan et al. 2016, section 3.1 "rgbd odometry"
// so3 step): before the dense 6-DoF solve, the rotation alone is fitted photometrically on the coarsest levels,
// treating the scene as far away so each pixel moves by the homography K R K^-1. A rotation of 10-15 degrees
// between frames moves the image by 60-90 px at 640x480, beyond the reach of a photometric term whose gradients
// span a few pixels even at 80x60; the rotation-only problem has 3 unknowns, reads every pixel with colour (depth
// or not) and has a far wider basin, so the dense solve then starts within its own.
//
// The residual of current pixel p is r = I_ref(pi(K R K^-1 p~)) - I_cur(p) - b (intensities in [0, 1], bilinear,
// pixels landing outside the reference skipped; b the median difference, a brightness offset) with
// J = grad I_ref . d pi / d q . (-[q]x), q = R K^-1 p~, for the left update R <- exp(omega) R; rows are weighted by
// Huber's at 1.345 sigma (sigma = 1.4826 median |r|). Gauss-Newton on the 3x3 system in double.
//
// Thread-safety: a pure function.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "registration/frame_pyramid.h"

namespace hf {

struct So3PrealignResult {
  Eigen::Matrix3d R_ref_cur = Eigen::Matrix3d::Identity();
  bool accepted = false;         // the fit lowered the robust cost and is well conditioned; else R_ref_cur = R_initial
  long pixels = 0;               // rows of the last iteration (finest level used)
  double cost_before = 0.0, cost_after = 0.0;  // mean Huber cost at R_initial and at the result (finest level used)
};

// Fits the rotation of current onto reference from R_initial on levels L-1 .. L-iterations.size() of both
// pyramids (iterations[0] for the coarsest), L = min(levels, both pyramids' levels): the levels a dense solve of
// `levels` levels uses. Needs intensity and gradients in both (else returns R_initial, not accepted). Never throws;
// never returns a non-finite rotation.
So3PrealignResult so3_prealign(const FramePyramid& current, const FramePyramid& reference,
                               const Eigen::Matrix3d& R_initial, const std::vector<int>& iterations, int levels);

// GaussNewtonOptions::so3_iterations wherever the wide basin is on (combined's align() defaults, the SLAM pipeline's
// frames without a motion prior, bench_pairs' "so3" variants): 10 and 5 on the two coarsest levels, chosen on TUM
// fr1/rpy 0-149 pairs (bench/results/accuracy/large_motion.md).
inline std::vector<int> wide_basin_so3_iterations() { return {10, 5}; }

}  // namespace hf
