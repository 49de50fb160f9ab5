#include "slam/config_reference.h"

#include <limits>

#include "core/number_text.h"

namespace hf::slam {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// Shorthands for the rows: [lo, hi], (lo, hi], ... A text or bool key takes any().
struct Range {
  double min, max;
  bool min_open, max_open;
};
constexpr Range closed(double lo, double hi) { return {lo, hi, false, false}; }
constexpr Range at_least(double lo) { return {lo, kInf, false, false}; }
constexpr Range above(double lo) { return {lo, kInf, true, false}; }
constexpr Range open_closed(double lo, double hi) { return {lo, hi, true, false}; }
constexpr Range open(double lo, double hi) { return {lo, hi, true, true}; }
constexpr Range any() { return {-kInf, kInf, false, false}; }

ConfigKey row(const char* key, const char* unit, Range r, const char* meaning) {
  return {key, unit, r.min, r.max, r.min_open, r.max_open, meaning};
}

std::vector<ConfigKey> make_reference() {
  return {
      // Top level: what tracks, and the failure policy (slam/pipeline.h).
      row("registration", "", any(),
          "the tracking method: a registry name (hashfusion config --registration NAME) or groundtruth"),
      row("fallback_registration", "", any(),
          "tried when the method fails or disagrees with the map (empty: none)"),
      row("seed_registration", "", any(), "runs first on every frame to seed large motions (empty: off)"),
      row("seed_min_motion_m", "m", at_least(0), "the seed replaces the motion prior when they differ by more"),
      row("seed_min_motion_deg", "deg", at_least(0), "the same for rotation"),
      row("seed_on_failure", "", any(),
          "runs once where no registration placed the frame; the method retries from it (empty: off)"),
      row("backend", "", any(), "where the normal equations are reduced: cpu | opencl"),
      row("tracking_level", "", closed(0, 2), "pyramid level tracking starts at: 0 full, 1 half, 2 quarter"),
      row("constant_velocity", "", any(), "guess each motion as the last one (false: identity, KinectFusion)"),
      row("velocity_by_time", "", any(), "scale the last motion by the frames' time stamps (covers dropped frames)"),
      row("wide_basin_without_prior", "", any(),
          "with no motion prior (after a loss): one more coarse level and the rotation-first step"),
      row("max_speed_m_per_s", "m/s", above(0), "a faster camera motion is a tracking failure"),
      row("max_angular_speed_deg_per_s", "deg/s", above(0), "the same for rotation"),
      row("max_degenerate_dims", "", closed(0, 6), "more unconstrained motion directions than this: lost"),
      row("integrate_poor", "", any(), "fuse frames whose registration is poor"),
      row("model_hint", "", any(), "seed the tracking raycast with the last raycast moved to the new pose"),
      row("tracking_raycast", "", any(), "full (every pixel) | sampled (the registration's selected pixels)"),
      row("tracking_raycast_dilate_px", "px", closed(0, 16), "sampled raycast: the selection grown by this"),
      row("min_overlap", "", closed(0, 1), "share of sampled depth on the model for the consistency check to run"),
      row("min_consistent", "", closed(0, 1), "share of the overlap that must agree with the model, else lost"),
      row("stream_radius_m", "m", at_least(0), "blocks farther from the camera go to the host store (0: off)"),
      // volume (fusion/voxel_block_grid.h)
      row("volume.voxel_m", "m", closed(1e-4, 10), "edge of a voxel"),
      row("volume.truncation_vox", "voxels", closed(1, 64), "TSDF truncation distance mu"),
      row("volume.max_weight", "", closed(1, 4095), "cap of a voxel's fusion weight (older frames fade beyond it)"),
      row("volume.capacity_blocks", "blocks", closed(1, 67108864), "voxel block pool, 4 KiB per block"),
      // integrate (fusion/integrate.h)
      row("integrate.min_depth_m", "m", at_least(0), "nearer depth is not fused (sensor minimum range)"),
      row("integrate.max_depth_m", "m", above(0), "farther depth is not fused (noise grows as depth squared)"),
      row("integrate.observation_weight", "", above(0), "weight of each observation in the running average"),
      row("integrate.point_to_plane", "", any(), "signed distance along the surface normal, not the ray"),
      row("integrate.truncation_depth_ref_m", "m", at_least(0), "band mu (d / this)^2 nearer than this (0: off)"),
      row("integrate.truncation_min_fraction", "", open_closed(0, 1), "the narrowest band, a fraction of mu"),
      row("integrate.weight_depth_ref_m", "m", at_least(0), "observations beyond this weigh (this / d)^2 (0: off)"),
      // raycast (fusion/raycast.h): the tracking raycast
      row("raycast.min_depth_m", "m", above(0), "rays start this far from the camera"),
      row("raycast.max_depth_m", "m", above(0), "and end this far"),
      row("raycast.step_fraction", "", open(0, 1), "step as a fraction of the signed distance bound"),
      row("raycast.min_step_vox", "voxels", open_closed(0, 4), "smallest step near the surface"),
      row("raycast.min_weight", "", at_least(0), "voxels of a smaller weight count as unobserved"),
      row("raycast.refine_tol_vox", "voxels", open_closed(0, 1), "the zero crossing is refined to this"),
      // pyramid (registration/frame_pyramid.h)
      row("pyramid.levels", "", closed(1, 6), "pyramid levels registration runs on (at most; one iteration count each)"),
      row("pyramid.bilateral_filter", "", any(), "bilateral filter on the finest depth (KinectFusion eq. 2)"),
      row("pyramid.max_depth_m", "m", at_least(0), "depth beyond this is dropped (0: keep all)"),
      row("pyramid.min_depth_m", "m", at_least(0), "depth below this is dropped"),
      row("pyramid.fill_holes_levels", "", closed(0, 8), "fill depth holes from coarser levels (0: off)"),
      // keyframes (slam/keyframes.h)
      row("keyframes.min_translation_m", "m", above(0), "a new keyframe after this much motion"),
      row("keyframes.min_rotation_deg", "deg", above(0), "or this much rotation"),
      row("keyframes.max_frames_between", "frames", at_least(1), "or at least this often while tracking"),
      row("keyframes.memory_budget_mb", "MiB", at_least(0), "compressed images of all keyframes together"),
      row("keyframes.jpeg_quality", "", closed(1, 100), "JPEG quality of the keyframes' colour images"),
      // relocalisation
      row("relocalisation.enabled", "", any(), "register lost frames against keyframes found by appearance"),
      row("relocalisation.candidates", "", closed(1, 100), "keyframes tried per lost frame"),
      row("relocalisation.appearance", "", any(), "appearance index (slam/appearance.h; empty: the default)"),
      // loop_closure (slam/loop_closure.h, slam/pose_graph.h)
      row("loop_closure.enabled", "", any(), "close loops on the keyframe pose graph"),
      row("loop_closure.candidates", "", closed(1, 50), "appearance matches verified per new keyframe"),
      row("loop_closure.min_keyframe_gap", "keyframes", at_least(1), "candidates are at least this much older"),
      row("loop_closure.min_path_m", "m", at_least(0), "camera path since the candidate, at least"),
      row("loop_closure.max_distance_m", "m", above(0), "pose proximity of a candidate"),
      row("loop_closure.max_angle_deg", "deg", open_closed(0, 180), "and its rotation"),
      row("loop_closure.min_inlier_ratio", "", closed(0, 1), "the verifying registration's inlier ratio"),
      row("loop_closure.min_consistent", "", closed(0, 1), "share of the overlapping depth that must agree"),
      row("loop_closure.loop_loss_chi2", "", above(0), "robust loss scale of loop edges (chi-square, 6 dof)"),
      row("loop_closure.loop_reject_chi2", "", above(0), "a loop edge beyond this after the solve is dropped"),
      row("loop_closure.max_iterations", "", closed(1, 10000), "Levenberg-Marquardt iterations per solve"),
      row("loop_closure.time_budget_ms", "ms", above(0), "wall-clock budget of one graph optimisation"),
      row("loop_closure.background", "", any(), "run the back-end on its own thread (hf-backend)"),
      row("loop_closure.apply_delay_frames", "frames", closed(1, 10000), "a job started at frame s lands at s + this"),
      row("loop_closure.window_keyframes", "keyframes", closed(0, 50),
          "keyframe window edges: each new keyframe also registered to keyframes k-2 .. k-this (0 = off)"),
      row("loop_closure.window_information_scale", "", open_closed(0, 1e6), "window edges' information scale"),
      row("loop_closure.window_tracking_information_scale", "", closed(0, 1e6),
          "with window edges: the tracked keyframe steps kept in the graph, information times this (0 = not)"),
      // reintegration (slam/reintegration.h)
      row("reintegration.enabled", "", any(), "re-fuse frames whose pose a loop closure moved"),
      row("reintegration.min_translation_m", "m", at_least(0), "a correction must also move this much (0: off)"),
      row("reintegration.min_rotation_deg", "deg", at_least(0), "or rotate this much (0: off)"),
      row("reintegration.frames_per_step", "frames", closed(0, 1000), "re-fusions per processed frame, offline"),
      row("reintegration.frames_after_loop", "frames", closed(0, 100000), "re-fusions right after a closure"),
      row("reintegration.frames_after_loop_per_step", "frames", closed(1, 100000),
          "of those, at most this many per frame from the closure on"),
      row("reintegration.budget_ms_per_frame", "ms", at_least(0), "re-fusion time per frame in real time"),
      row("reintegration.min_displacement_vox", "voxels", at_least(0), "re-fuse a frame that moved more than this"),
      row("reintegration.memory_budget_mb", "MiB", at_least(0), "compressed images kept for re-fusion"),
      // colour_check (slam/colour_check.h)
      row("colour_check.enabled", "", any(), "judge from the frames whether colour is registered to depth"),
      row("colour_check.window_estimates", "", closed(1, 100000), "estimates whose median decides"),
      row("colour_check.frame_step", "frames", closed(1, 100000), "one estimate every this many frames"),
      row("colour_check.max_scale_error", "", open(0, 1), "|median zoom - 1| beyond this: unregistered"),
      row("colour_check.max_zoom", "", open_closed(1, 2), "the zoom searched, 1 / max_zoom .. max_zoom"),
      row("colour_check.max_shift_fraction", "", closed(0, 0.25), "the shift searched, of the image width"),
      row("colour_check.min_edge_fraction", "", open(0, 1), "share of pixels on depth edges for an estimate"),
      row("colour_check.max_chamfer_px", "px", open(0, 3), "an estimate's mean edge distance, at most"),
      row("colour_check.depth_only_registration", "", any(), "what tracks once colour is judged unregistered"),
      // registration_options: the driver (registration/registration.h GaussNewtonOptions), every method
      row("registration_options.iterations", "", any(), "iterations per pyramid level, finest first"),
      row("registration_options.min_step_rotation_rad", "rad", at_least(0), "a level stops below this step"),
      row("registration_options.min_step_translation_m", "m", at_least(0), "and below this translation"),
      row("registration_options.degeneracy_threshold", "", at_least(0), "directions weaker than this are frozen"),
      row("registration_options.min_inliers", "", at_least(0), "fewer rows at the finest level: failed"),
      row("registration_options.poor_inlier_ratio", "", closed(0, 1), "inlier ratio below this: poor"),
      row("registration_options.max_translation_m", "m", above(0), "a larger step from the guess: failed"),
      row("registration_options.max_rotation_deg", "deg", above(0), "the same for rotation"),
      row("registration_options.verify_motion_m", "m", at_least(0), "larger motions are verified backwards"),
      row("registration_options.verify_motion_deg", "deg", at_least(0), "the same for rotation"),
      row("registration_options.verify_agreement_m", "m", at_least(0), "forward and backward must agree to this"),
      row("registration_options.verify_agreement_deg", "deg", at_least(0), "and in rotation to this"),
      row("registration_options.max_final_step_translation_m", "m", at_least(0), "a larger last step: failed"),
      row("registration_options.max_final_step_rotation_rad", "rad", at_least(0), "the same for rotation"),
      row("registration_options.so3_iterations", "", any(),
          "rotation-first iterations per coarsest level ([] off)"),
      row("registration_options.row_selection", "", closed(0, 2), "rows from 0 all, 1 important, 2 uniform pixels"),
      row("registration_options.row_selection_tile_px", "px", closed(2, 64), "selection tile side"),
      row("registration_options.row_selection_budget", "", at_least(1), "pixels kept per tile"),
      row("registration_options.row_selection_depth_edge_weight", "", at_least(0), "depth steps against gradient"),
      row("registration_options.row_selection_levels", "", at_least(1), "finest levels the selection applies to"),
      // icp (registration/icp.h)
      row("registration_options.max_dist_m", "m", above(0), "icp: correspondences farther apart are rejected"),
      row("registration_options.max_normal_angle_deg", "deg", open_closed(0, 180), "icp: or with normals this far"),
      row("registration_options.robust_icp", "", any(), "icp: IRLS kernel none | huber | student_t"),
      row("registration_options.huber_icp_m", "m", above(0), "icp: Huber threshold"),
      row("registration_options.t_sigma_icp_m", "m", above(0), "icp: Student-t scale"),
      row("registration_options.t_dof_icp", "", above(0), "icp: Student-t degrees of freedom"),
      row("registration_options.depth_noise_ref_m", "m", at_least(0), "icp: rows beyond this weighed by noise (0: off)"),
      // photometric (registration/photometric.h)
      row("registration_options.robust_rgb", "", any(), "photometric: IRLS kernel none | huber | student_t"),
      row("registration_options.huber_rgb", "", above(0), "photometric: Huber threshold (intensity 0..1)"),
      row("registration_options.t_dof", "", above(0), "photometric: Student-t degrees of freedom"),
      row("registration_options.t_sigma_rgb_init", "", above(0), "photometric: Student-t scale to start from"),
      row("registration_options.t_sigma_rgb_min", "", above(0), "photometric: floor of that scale"),
      row("registration_options.min_gradient", "", at_least(0), "photometric: flatter pixels give no rows"),
      row("registration_options.photometric_occlusion_check", "", any(), "photometric: reject occluded pixels"),
      row("registration_options.occlusion_max_depth_m", "m", above(0), "photometric: depth mismatch = occluded"),
      row("registration_options.finest_level_photometric_step", "px", closed(1, 16), "photometric: finest stride"),
      row("registration_options.brightness_gain", "", any(), "photometric: estimate an exposure gain"),
      row("registration_options.brightness_gain_max_ratio", "", at_least(0), "photometric: when the gain explains"),
      // combined (registration/combined.h)
      row("registration_options.rgb_weight", "", at_least(0), "combined: lambda, photometric rows against icp's"),
      row("registration_options.icp_term_threshold", "", closed(0, 1), "combined: icp's weak directions dropped"),
      row("registration_options.photometric_term_threshold", "", closed(0, 1), "combined: the same, photometric"),
      row("registration_options.icp_probe_ratio", "", closed(0, 1), "combined: probe icp's weak directions (0: off)"),
      row("registration_options.icp_probe_step_m", "m", above(0), "combined: probe step"),
      row("registration_options.icp_probe_min_ratio", "", at_least(0), "combined: observed/claimed curvature"),
      row("registration_options.icp_probe_photometric_ratio", "", closed(0, 1), "combined: photometric support"),
      row("registration_options.clean_scale_rgb", "", at_least(0), "combined: photometric scale of a clean sequence"),
      row("registration_options.scale_history", "", closed(1, 1000), "combined: registrations the scale is over"),
      row("registration_options.scale_history_min", "", at_least(1), "combined: fewer: the default regime"),
      row("registration_options.clean_t_dof", "", above(0), "combined: clean regime's Student-t dof"),
      row("registration_options.clean_t_sigma_rgb_min", "", above(0), "combined: clean regime's scale floor"),
      row("registration_options.clean_rgb_weight_gain", "", at_least(0), "combined: clean regime's lambda factor"),
  };
}

}  // namespace

const std::vector<ConfigKey>& config_reference() {
  static const std::vector<ConfigKey> rows = make_reference();
  return rows;
}

const ConfigKey* find_config_key(const std::string& key) {
  for (const ConfigKey& r : config_reference())
    if (key == r.key) return &r;
  return nullptr;
}

bool in_config_range(const ConfigKey& r, double v) {
  const bool lo = r.min_open ? v > r.min : v >= r.min;
  const bool hi = r.max_open ? v < r.max : v <= r.max;
  return lo && hi && v == v;  // NaN is in no range
}

std::string describe_range(const ConfigKey& r) {
  const std::string unit = *r.unit ? std::string(" ") + r.unit : std::string();
  if (r.min == -kInf && r.max == kInf) return "";
  if (r.max == kInf) return (r.min_open ? "> " : ">= ") + number_for_message(r.min) + unit;
  if (!r.min_open && !r.max_open) return number_for_message(r.min) + ".." + number_for_message(r.max) + unit;
  return std::string(r.min_open ? "(" : "[") + number_for_message(r.min) + ", " + number_for_message(r.max) +
         (r.max_open ? ")" : "]") + unit;
}

}  // namespace hf::slam
