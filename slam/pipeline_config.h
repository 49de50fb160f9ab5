// The pipeline's configuration (slam/pipeline.h): one value type with documented defaults, validated as a whole,
// and its JSON form (a config file, and the "config" of report.json).
//
//   PipelineConfig c = load_config("my.json");   // defaults overridden by the keys present
//   c.validate();                                // hf::Error naming the bad field
//
// Each nested section (volume, integrate, raycast, pyramid, registration_options, keyframes, relocalisation,
// loop_closure, reintegration, colour_check) is a JSON object of the same name; an unknown key anywhere is an
// error naming it, so a typo never silently keeps a default.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>

#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"
#include "registration/frame_pyramid.h"
#include "registration/registration.h"
#include "slam/colour_check.h"
#include "slam/keyframes.h"
#include "slam/loop_closure.h"
#include "slam/reintegration.h"

namespace hf::slam {

// Relocalisation (slam/pipeline.h, "Failure policy"): what a lost frame is registered against.
struct RelocalisationOptions {
  bool enabled = true;
  int candidates = 5;       // keyframes retrieved by appearance per lost frame, each registered and verified
  std::string appearance;   // appearance index (slam/appearance.h); empty = default_appearance_index_name()
};

struct PipelineConfig {
  std::string registration = "combined";  // a registry name (make_registration) or "groundtruth"
  // Tried against the same model reference when `registration` fails or its result disagrees with the map: the
  // geometric rows alone cannot be led astray by a bad colour frame or unregistered colour. Empty = none; unused
  // when it equals `registration`.
  std::string fallback_registration = "icp";
  // Seeding for large motions: this registry method (normally "sparse", whose answer does not depend on the guess)
  // runs first on every frame against the same reference; where its usable estimate differs from the motion prior
  // by more than seed_min_motion_m or seed_min_motion_deg, `registration` (and the fallback) start from it instead.
  // Empty = off, the default: it costs the seed's time on every frame (bench/results/sparse.md measures both);
  // seed_on_failure below runs the same method on rejected frames only.
  std::string seed_registration;
  double seed_min_motion_m = 0.03;    // well above a converged dense estimate's disagreement with sparse (~5 mm)
  double seed_min_motion_deg = 3.0;
  // Seeding on failure (issue 34, large motion): where neither `registration` nor the fallback placed the frame
  // (lost, or odometry only), this registry method runs once against the same reference; where its estimate is
  // plausible (the failure policy's usable / degenerate / speed tests), `registration` runs again from it (then
  // the fallback), and the retry decides the frame where it does better. Its cost (sparse: ORB, ~25 ms) lands on
  // rejected frames only; where the primary is accepted it never runs (FrameResult::seeded_on_failure). Default
  // "sparse": it tracks the `fast` preset (15 degrees and 10 cm a frame) that dense methods lose from the identity
  // and leaves the real sequences as they were (bench/results/accuracy/large_motion.md). It also cross-checks a
  // frame without a motion prior that the wide basin placed (wide_basin_without_prior below): the retry from its
  // estimate replaces that placement where its cost is lower. Empty = off.
  std::string seed_on_failure = "sparse";
  std::string backend = "cpu";             // reduction backend: cpu | opencl
  fusion::VolumeParams volume;             // voxel_m 0.01, truncation 4 voxels, capacity, weight cap
  fusion::IntegrateParams integrate;
  // The tracking raycast. No shading and no colour: tracking reads neither (photometric rows are frame to frame;
  // render() turns shading on for its own raycast). The crossing is refined to 0.05 voxel, not to raycast's
  // default 0.001 (which exists so hinted and full marches agree exactly): on fr1/rpy the ATE is the same to 1 um
  // and the raycast ~10-15 % cheaper (bench/results/pipeline.md).
  fusion::RaycastOptions raycast{.refine_tol_vox = 0.05, .shade = false, .color = false};
  // Where the frame has no depth, hint the tracking raycast with the last model raycast moved to the new pose
  // (fusion::forward_project_depth) instead of marching those rays from the near end of their tile.
  bool model_hint = true;
  // The tracking raycast: "full" (every pixel) or "sampled" (fusion/raycast_sampled.h: only the pixels the
  // registration's row selection, GaussNewtonOptions::row_selection, keeps in this frame, grown by
  // tracking_raycast_dilate_px for the motion to the next frame; a selection of `all` casts every valid pixel's
  // ray). Integration and render() always raycast in full. Measured in bench/results/fewer_rays_tracking.md.
  std::string tracking_raycast = "full";
  int tracking_raycast_dilate_px = 2;
  FramePyramidOptions pyramid;
  // The pyramid level tracking starts at: 0 = full resolution; 1 = half (DVO-SLAM tracked at 320x240 in real time
  // on one core). Tracking then uses pyramid.levels levels from there, and the model is raycast at that resolution;
  // integration always uses the full-resolution frame. Default 1, measured on TUM fr1/rpy (150 frames, combined):
  // ATE 1.87 cm at 2.9 fps from level 1 against 2.29 cm at 1.0 fps from level 0 (bench/results/pipeline.md): the
  // full-resolution level adds cost, and with motion blur and rolling shutter no accuracy.
  int tracking_level = 1;
  // Registration options; unset = pipeline_registration_options(registration). Every registration knob lives
  // here, once (the JSON section "registration_options"); a former top-level "rgb_weight" is read into it.
  std::optional<RegistrationOptions> registration_options;
  // Motion prior: the initial guess of T_ref_cur is the last inter-frame motion (constant velocity) when true, the
  // identity (KinectFusion) when false. Never used right after a lost frame.
  bool constant_velocity = true;
  // The constant velocity is per second of sensor time, not per frame: the last motion is scaled by the ratio of
  // this frame's interval to the last pair's (at most 5), so after dropped frames the guess covers the gap. Where
  // the stamps are a frame counter (7-Scenes) the ratio is 1.
  bool velocity_by_time = false;
  // Where the pipeline has no motion prior (the frame after initialisation, a lost frame or a relocalisation: the
  // guess is the identity, and the motion since the reference is unknown and may be large), the primary runs with
  // a wider basin: one coarser pyramid level and the rotation-first step (pipeline_wide_basin_options). On pairs of
  // real frames 3 and 5 apart from the identity it converges on 99 / 85 % against 89 / 22 % (fr1/rpy 150-269,
  // bench/results/accuracy/large_motion.md); on consecutive frames from the prior it costs time and no accuracy,
  // so it never runs there. Only with constant_velocity: without it the identity is the chosen prior (KinectFusion).
  // From far it can settle in a wrong minimum the map's depth does not refute; seed_on_failure cross-checks it.
  bool wide_basin_without_prior = true;
  // Plausibility (per second of sensor time since the last good frame): a faster motion is a tracking failure.
  // The gate rejects wild registrations, not fast hands: hand-held motion bursts reach a few hundred deg/s (the
  // recordings we hold peak at 179-193 deg/s and 1.1 m/s over 1/30 s), and the depth consistency check beside it
  // judges every estimate against the map. 720 deg/s and 6 m/s (24 degrees and 20 cm a frame at 30 Hz) admit the
  // `fast` preset's 450 deg/s and 3.1 m/s with margin; no frame of the real sequences is rejected by either gate,
  // so they track the same under both (bench/results/accuracy/large_motion.md).
  double max_speed_m_per_s = 6.0;
  double max_angular_speed_deg_per_s = 720.0;
  int max_degenerate_dims = 3;              // more unconstrained directions than this: lost
  bool integrate_poor = true;               // integrate frames whose registration is `poor`
  // Depth consistency (decide stage): the frame's depth, moved by the estimated motion, is compared with the model
  // depth it lands on (every 4th pixel). Where at least min_overlap of the sampled pixels land on the model, at
  // least min_consistent of those must agree within 3 sigma of the Kinect axial noise (Nguyen et al. 2012) plus
  // one voxel; else the depth is garbage (or the pose is wrong) and the frame is lost. Photometric rows can track a
  // frame whose depth is broken, so the pose alone does not protect the map.
  double min_overlap = 0.2;
  double min_consistent = 0.5;
  // Streaming (Niessner et al. 2013): blocks farther than this from the camera go to the host store after each
  // frame; 0 = off.
  double stream_radius_m = 0.0;
  KeyframeOptions keyframes;
  RelocalisationOptions relocalisation;
  LoopClosureOptions loop_closure;
  ReintegrationOptions reintegration;
  // Whether the colour is registered to the depth, judged from the frames themselves (slam/colour_check.h); when
  // it is not, tracking goes on with colour_check.depth_only_registration. Only while `registration` reads colour
  // (Registration::reads_colour); for a depth-only method the check stays undecided.
  ColourCheckOptions colour_check;
  // The options of colour_check.depth_only_registration once it takes over (the JSON section
  // "depth_only_registration_options", that method's keys); unset = pipeline_registration_options(that method).
  // Written to report.json only when set.
  std::optional<RegistrationOptions> depth_only_registration_options;

  // Throws hf::Error naming the bad field (also validates the nested option structs).
  void validate() const;
};

// JSON form of the whole configuration (written into report.json) and back. from_json starts from the defaults
// and overrides the keys present; an unknown key or a value of the wrong type throws hf::Error naming `where`
// (e.g. the config file) and the key.
nlohmann::json config_to_json(const PipelineConfig& config);
PipelineConfig config_from_json(const nlohmann::json& j, const std::string& where);
// Reads a JSON config file, or a report.json whose "config" object it takes; errors name the file (and line for
// JSON syntax errors).
PipelineConfig load_config(const std::string& path);
// The same from the file's text; `name` stands for the file in messages.
PipelineConfig parse_config(const std::string& text, const std::string& name);


// lambda of eq. 48 (combined's rgb_weight) in this pipeline, where it differs from the registration's own default:
// measured with frame-to-model ICP rows and frame-to-frame photometric rows on TUM fr1/rpy, 150 frames, 320x240
// tracking: ATE 3.06 cm at 0.1, 1.87 cm at 0.4, 2.14 cm at 1.0 (bench/results/pipeline.md). The registration's 0.1
// is the optimum of the frame-to-frame sweep, where the ICP reference is as sharp as the frame; the fused model's
// smoother geometry shifts the balance towards the photometric rows.
inline constexpr double kPipelineRgbWeight = 0.4;

// A method's options as the pipeline runs it: its defaults, with rgb_weight = kPipelineRgbWeight where it has one,
// without the registry's wide-basin settings for guess-free pairs (no rotation-first step: the pipeline tracks from
// a motion prior; bench/results/accuracy/large_motion.md) and at most `levels` iteration counts, one per level of
// the pipeline's pyramid (PipelineConfig::pyramid.levels; the registry's defaults for guess-free pairs may hold
// more). Never more levels than the registry gives: for some methods a count is a resolution of their own.
RegistrationOptions pipeline_registration_options(const std::string& method,
                                                  int levels = FramePyramidOptions{}.levels);
// The options the pipeline tracks with where it has no motion prior (PipelineConfig::wide_basin_without_prior),
// from those it tracks with otherwise: one coarser level (its iterations the coarsest's, at least 4) and, for a
// method reading colour, the rotation-first step on the two coarsest levels (wide_basin_so3_iterations(), as
// combined's registry default). The caller builds the frame and model pyramids with the extra level.
RegistrationOptions pipeline_wide_basin_options(RegistrationOptions tracking);
// A registry method's options from a JSON object of its keys (as report.json's "registration_options"): the
// method's registry defaults (default_registration_options, not the pipeline's) overridden by the keys present,
// validated. hf::Error naming `where` and the key for an unknown key, a wrong type or a value out of range.
RegistrationOptions registration_options_from_json(const std::string& method, const nlohmann::json& j,
                                                   const std::string& where);
// The registration options in force: registration_options when set, else pipeline_registration_options() for the
// configured pyramid's levels.
RegistrationOptions effective_registration_options(const PipelineConfig& config);

}  // namespace hf::slam
