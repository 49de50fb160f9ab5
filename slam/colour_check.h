// Is the colour registered to the depth? Decided from the data while tracking (issue 13), not told.
//
// A dataset whose colour camera was never calibrated against its depth camera (7-Scenes ships it so) hands out
// colour pixels that do not show the surface point their depth pixel measures. The photometric rows of `combined`
// then pull the pose away from where the geometric rows put it, and the pose is worse than the geometry alone
// gives (7-Scenes: combined 2.60 cm against icp's 2.17 cm, bench/results/tracking.md).
//
// The evidence (estimate_colour_alignment): within one frame, depth discontinuities are also intensity edges where
// the colour is registered. The similarity u_colour = s (u - c) + c + t that best lays the depth discontinuities
// onto the intensity edges (mean chamfer distance, truncated at 3 px) says where the colour camera looks: s = 1 for
// registered colour, s = f_colour / f_depth otherwise. A Kinect's colour camera has f ~525 px against its depth
// camera's ~585 px, so its raw colour reads s ~0.9, a zoom no motion produces; the shift t is not used, because a
// time offset between the two streams (TUM fr1 has up to 20 ms) shifts registered colour too under fast motion.
//
// The decision (ColourCheck): the median s over window_estimates frames; farther than max_scale_error from 1 and
// the colour is judged unregistered, and the pipeline tracks with depth alone from then on
// (PipelineConfig::colour_check). The verdict is taken once: a camera's calibration does not change mid-sequence,
// and a few black or alien colour frames move a median by a few ranks only. What it cannot see: colour from a camera
// with the depth camera's focal length but a baseline apart (a shift that varies with depth); such data reads as
// registered.
//
// Also here: the per-frame disagreement of a two-term registration's terms (term_disagreement), written to
// report.json for each frame as evidence people can read; on real data it does not separate the cases (TUM fr1/rpy,
// registered, reads a larger chi2 than 7-Scenes: bench/results/tracking.md, "Colour registration"), so the decision
// does not use it.
#pragma once

#include <string>
#include <vector>

#include "registration/frame_pyramid.h"
#include "registration/registration.h"

namespace hf::slam {

struct ColourCheckOptions {
  bool enabled = true;
  // Estimates whose median decides, one from every frame_step-th frame that gives one: 10 frames over ~1 s at
  // 30 Hz, so a sequence with unregistered colour is tracked by depth alone from about its 30th frame.
  int window_estimates = 10;
  int frame_step = 3;
  // |median s - 1| above this: unregistered. Chosen on TUM fr1/rpy frames 0-149 (registered: median 0.994) and
  // 7-Scenes frames 0-99 (unregistered: 0.906), about halfway; reported on fr1/rpy 150-269, fr1/desk, 7-Scenes 100-199 and the
  // synthetic room / unregistered presets (bench/results/tracking.md, "Colour registration").
  double max_scale_error = 0.05;
  // The search of the similarity: s in [1 / max_zoom, max_zoom], |t| <= max_shift_fraction of the image width.
  double max_zoom = 1.25;
  double max_shift_fraction = 1.0 / 16.0;
  // A frame gives an estimate only with at least this fraction of its pixels on depth discontinuities (a frame of
  // one wall has none) and a best mean chamfer distance below max_chamfer_px (pixels of the level it runs on).
  // 0.0065 (500 pixels at 320x240): the synthetic loop's outward views of a wall with one or two straight contours
  // (199-405 pixels) fit zooms of 0.78-0.84 with 15-20 px shifts, which judged its registered colour unregistered
  // at 0.0025; the real sequences' estimates have 430-2100 (TUM) and 900-1900 (7-Scenes) and read the same medians
  // at either value (bench/results/tracking.md, "Colour registration").
  double min_edge_fraction = 0.0065;
  double max_chamfer_px = 2.5;
  // What tracks once the colour is judged unregistered: a registry method that reads no colour. sdf (direct
  // tracking against the TSDF, which also skips the tracking raycast), chosen on 7-Scenes 0-99 against icp: ATE
  // 1.04 vs 1.09 cm at 38 vs 44 ms a frame; reported on 100-199: 1.332 vs 1.326 cm (a tie), 38 vs 43 ms; 0-199
  // whole 1.95 vs 2.21 (bench/results/accuracy/depth_only.md).
  std::string depth_only_registration = "sdf";

  void validate() const;  // hf::Error naming the bad field
};

// One frame's colour-to-depth similarity: colour pixel = scale (u - c) + c + shift, u a depth pixel, c the
// principal point, in the pixels of the level it was estimated on. valid = false when the frame has no colour, too
// few depth discontinuities, or no fit (see ColourCheckOptions).
struct ColourAlignment {
  bool valid = false;
  double scale = 1.0;
  double shift_x_px = 0.0, shift_y_px = 0.0;
  double chamfer_px = 0.0;  // mean distance (truncated at 3 px) from the moved depth edges to intensity edges
  // How much larger the best mean distance is at any scale 0.05 or more away from `scale`: how well the contours
  // pin the zoom down (straight parallel contours fit any zoom with some shift).
  double zoom_contrast_px = 0.0;
  long depth_edges = 0;     // depth-discontinuity pixels used
};
ColourAlignment estimate_colour_alignment(const FramePyramidLevel& level, const ColourCheckOptions& options);

enum class ColourVerdict { undecided, registered, unregistered };
const char* to_string(ColourVerdict verdict);

class ColourCheck {
 public:
  explicit ColourCheck(const ColourCheckOptions& options);  // validates the options
  // Whether frame `frame_index` should be estimated (enabled, undecided, and its turn by frame_step).
  bool wants(size_t frame_index) const;
  // Adds one frame's estimate (ignored when !valid or once decided). True when this call decided.
  bool add(const ColourAlignment& estimate, size_t frame_index);
  ColourVerdict verdict() const { return verdict_; }
  double median_scale() const { return median_scale_; }  // of the window that decided; 1 before
  size_t decided_at_frame() const { return decided_at_; }
  const std::vector<double>& scales() const { return scales_; }

 private:
  ColourCheckOptions options_;
  std::vector<double> scales_;
  ColourVerdict verdict_ = ColourVerdict::undecided;
  double median_scale_ = 1.0;
  size_t decided_at_ = 0;
};

// One frame's disagreement between the "icp" and "photometric" terms of a registration (RegistrationResult::terms):
// each term's own Gauss-Newton step from the joint solution (Term::step) points at that term's optimum; d is their
// difference. With each term's noise from its residuals (sigma_t^2 = cost_t / rows_t) and covariance
// sigma_t^2 H_t^-1 (eigenvalues floored at 1e-9 of the largest, so a direction one term leaves free carries no
// evidence), chi2 = d^T (sigma_i^2 H_i^-1 + sigma_p^2 H_p^-1)^-1 d: chi-square with 6 degrees of freedom for two
// terms that measure one motion with independent noise. valid only when both terms are there and usable.
struct TermDisagreement {
  bool valid = false;
  double chi2 = 0.0;
  double translation_m = 0.0;      // |d_v|
  double rotation_deg = 0.0;       // |d_omega| in degrees
  double sigma_icp_m = 0.0;        // sqrt(cost / rows) of the icp term (metres)
  double sigma_photometric = 0.0;  // the same of the photometric term (intensity times its weight)
};
TermDisagreement term_disagreement(const RegistrationResult& result);

}  // namespace hf::slam
