#include "slam/pipeline.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/number_text.h"
#include "core/kernels/image_kernels.h"
#include "fusion/mesh.h"
#include "fusion/raycast_sampled.h"
#include "registration/pixel_selection.h"
#include "slam/consistency.h"
#ifdef HF_HAVE_FUSION_OPENCL
#include "fusion/opencl/device_voxel_grid.h"
#include "registration/opencl/device_pyramid.h"
#include "core/opencl/opencl_context.h"
#include "core/timing.h"
#endif

namespace hf::slam {
namespace {

// The intensity levels of `from` move onto the levels `to` has (the photometric reference); nothing else of
// `from` is needed again. The images keep their pixels' addresses, so their device copies (core/device_copy.h)
// move along.
void take_intensity(FramePyramid& from, FramePyramid* to) {
  for (int l = 0; l < to->num_levels() && l < from.num_levels(); ++l) {
    FramePyramidLevel& dst = to->levels[size_t(l)];
    FramePyramidLevel& src = from.levels[size_t(l)];
    for (Image<float> FramePyramidLevel::*image :
         {&FramePyramidLevel::intensity, &FramePyramidLevel::grad_x, &FramePyramidLevel::grad_y}) {
      dst.device_copies.drop((dst.*image).data());
      src.device_copies.move_to(dst.device_copies, (src.*image).data());
      dst.*image = std::move(src.*image);
    }
  }
}

// A frame's tracking pyramid: on the device where there is one (the pyramid stays there for the reductions), else
// on the host.
FramePyramid frame_pyramid([[maybe_unused]] opencl::DeviceFramePyramid* device, const DepthImage& depth,
                           const ColorImage& colour, const PinholeCamera& camera, const FramePyramidOptions& options) {
  const ColorImage* c = colour.empty() ? nullptr : &colour;
#ifdef HF_HAVE_FUSION_OPENCL
  if (device != nullptr) return device->build(depth, c, camera, options);
#endif
  return build_frame_pyramid(depth, c, camera, options);
}

// The reference pyramid of the model maps: on the device where the raycast left them there (the device pyramid
// binds their copies, and the levels stay there for the reduction), else on the host.
FramePyramid model_pyramid([[maybe_unused]] opencl::DeviceFramePyramid* device, const fusion::RaycastResult& model,
                           const PinholeCamera& camera, int levels) {
#ifdef HF_HAVE_FUSION_OPENCL
  if (device != nullptr && !model.device_copies.empty())
    return device->build_model(model.vertices, model.normals, camera, levels);
#endif
  return build_model_pyramid(model.vertices, model.normals, nullptr, camera, levels);
}

}  // namespace

const char* to_string(TrackState state) {
  switch (state) {
    case TrackState::initialised: return "initialised";
    case TrackState::tracked: return "tracked";
    case TrackState::recovered: return "recovered";
    case TrackState::relocalised: return "relocalised";
    case TrackState::odometry: return "odometry";
    case TrackState::lost: return "lost";
    case TrackState::groundtruth: return "groundtruth";
  }
  return "?";
}


// --- The pipeline -----------------------------------------------------------------------------------------------

// Everything tracking aligns against, all in the camera frame of the last pose.
struct Pipeline::Reference {
  fusion::RaycastResult model;   // raycast of the map at the last pose
  SE3 T_world_model;             // that pose
  FramePyramid pyramid;          // model vertices/normals per level + the last frame's intensity/gradients
  bool valid = false;
  // The primary method aligns to the map itself (Registration::aligns_to_volume): the pose moved on without a
  // raycast, so model and pyramid are not of T_world_model; cast on demand (ensure_reference_maps), with the
  // last frame's intensity levels kept here meanwhile.
  bool stale = false;
  FramePyramid frame_intensity;
};

// What decide() concluded for one frame; applied by process() only after it is final.
struct Pipeline::Verdict {
  enum Action { integrate, odometry, lose } action = lose;
  SE3 T_world_cur;
  TrackState state = TrackState::lost;
  std::optional<RegistrationResult> registration;
  std::string method, why;
};

// pipeline_wide_basin_options, without its extra level where that level would be narrower than 20 px (a
// tracking resolution of 160x120 with 3 levels): too few pixels for the rotation fit and the dense solve.
RegistrationOptions Pipeline::wide_basin_options(const RegistrationOptions& tracking) const {
  RegistrationOptions wide = pipeline_wide_basin_options(tracking);
  const int levels = int(wide.driver.iterations.size());
  if (levels > config_.pyramid.levels && (tracking_camera_.width >> (levels - 1)) < 20)
    wide.driver.iterations.resize(size_t(std::max(config_.pyramid.levels, int(tracking.driver.iterations.size()))));
  return wide;
}

Pipeline::Pipeline(const PipelineConfig& config, const PinholeCamera& camera)
    : config_(config), camera_(camera.pinhole()), tracking_camera_(camera.pinhole().scaled(config.tracking_level)),
      grid_((config.validate(), config.volume)),
      colour_check_(config.colour_check), reference_(std::make_unique<Reference>()), keyframes_(config.keyframes),
      fused_(config.reintegration) {
  if (!camera.distortion.none()) undistorter_ = std::make_unique<Undistorter>(camera);
#ifdef HF_HAVE_FUSION_OPENCL
  if (config_.backend == "opencl" && config_.stream_radius_m <= 0)
    device_map_ = std::make_unique<fusion::DeviceVoxelGrid>(config_.volume);
  // The frame pyramid on the device too, unless it fills holes (push-pull has no device kernel).
  if (config_.backend == "opencl" && config_.pyramid.fill_holes_levels == 0)
    device_pyramid_ = std::make_unique<opencl::DeviceFramePyramid>();
#endif
  if (config_.registration == "groundtruth") return;
  RegistrationOptions options = effective_registration_options(config_);
  std::vector<int>& iterations = options.driver.iterations;
  if (int(iterations.size()) > config_.pyramid.levels) iterations.resize(size_t(config_.pyramid.levels));
  config_.registration_options = options;
  registration_ = make_registration(config_.registration, options, make_backend(config_.backend));
  tracking_levels_ = config_.pyramid.levels;
  if (config_.wide_basin_without_prior && config_.constant_velocity) {
    const RegistrationOptions wide = wide_basin_options(options);
    tracking_levels_ = std::max(tracking_levels_, int(wide.driver.iterations.size()));
    wide_ = make_registration(config_.registration, wide, make_backend(config_.backend));
  }
  // Every method the pipeline runs starts from the pipeline's settings (pipeline_registration_options), never from
  // a registry default meant for guess-free pairs (combined's rotation-first step and five levels).
  if (!config_.fallback_registration.empty() && config_.fallback_registration != config_.registration) {
    RegistrationOptions fo = pipeline_registration_options(config_.fallback_registration);
    fo.driver.iterations = iterations;
    fallback_ = make_registration(config_.fallback_registration, fo, make_backend(config_.backend));
  }
  if (!config_.seed_registration.empty()) {
    RegistrationOptions so = pipeline_registration_options(config_.seed_registration, config_.pyramid.levels);
    seed_ = make_registration(config_.seed_registration, so, make_backend(config_.backend));
  }
  if (!config_.seed_on_failure.empty()) {
    RegistrationOptions so = pipeline_registration_options(config_.seed_on_failure, config_.pyramid.levels);
    failure_seed_ = make_registration(config_.seed_on_failure, so, make_backend(config_.backend));
  }
  if (config_.relocalisation.enabled)
    appearance_ = make_appearance_index(config_.relocalisation.appearance.empty()
                                            ? default_appearance_index_name()
                                            : config_.relocalisation.appearance);
  if (config_.loop_closure.enabled && appearance_) {
    loop_closer_ = std::make_unique<LoopCloser>(config_.loop_closure, config_.pyramid, config_.tracking_level, camera_,
                                                config_.volume.voxel_m);
    if (config_.loop_closure.background) backend_thread_ = std::make_unique<BackendThread>("hf-backend");
  }
}

Pipeline::~Pipeline() = default;

FrameResult Pipeline::process(const RgbdFrame& input) {
  const RgbdFrame& frame = input;  // checked as given, then (with a distorted camera) undistorted below
  if (frame.depth.width() != camera_.width || frame.depth.height() != camera_.height)
    throw Error((frame.depth_file.empty() ? "frame " + std::to_string(frame.index) : frame.depth_file) +
                ": depth is " + std::to_string(frame.depth.width()) + "x" + std::to_string(frame.depth.height()) +
                ", camera is " + std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  if (!frame.color.empty() && (frame.color.width() != camera_.width || frame.color.height() != camera_.height))
    throw Error((frame.color_file.empty() ? "frame " + std::to_string(frame.index) : frame.color_file) +
                ": colour size differs from the camera's");
  ++frames_;
  FrameResult r;
  r.index = frame.index;
  r.timestamp_s = frame.timestamp_s;
  if (undistorter_) return process_pinhole(undistort(input, &r), std::move(r));
  return process_pinhole(input, std::move(r));
}

// Undistorts a distorted camera's frame (core/undistort.h), timed into `preprocess`: every later stage and every
// stored copy (keyframes, re-fusion) sees the pinhole camera_.
RgbdFrame Pipeline::undistort(const RgbdFrame& input, FrameResult* r) const {
  const auto t0 = std::chrono::steady_clock::now();
  RgbdFrame frame;
  frame.index = input.index;
  frame.timestamp_s = input.timestamp_s;
  frame.depth = undistorter_->depth(input.depth);
  frame.color = undistorter_->color(input.color);
  frame.T_world_camera_gt = input.T_world_camera_gt;
  frame.depth_file = input.depth_file;
  frame.color_file = input.color_file;
  frame.arrival = input.arrival;
  r->ms.undistort = r->ms.preprocess = ms_since(t0);
  return frame;
}

FrameResult Pipeline::process_pinhole(const RgbdFrame& frame, FrameResult r) {

  if (!registration_) {  // groundtruth: fusion only
    if (!frame.T_world_camera_gt) {
      lose(&r, "no ground-truth pose for this frame");
    } else {
      r.state = TrackState::groundtruth;
      r.T_world_camera = *frame.T_world_camera_gt;
      r.pose_valid = true;
      integrate(frame, r.T_world_camera, &r);
      T_world_cur_ = r.T_world_camera;
      last_time_s_ = frame.timestamp_s;
    }
    record_anchor(r);
    return r;
  }

  finish_loop_job(false, &r);  // a back-end result due now moves the poses before this frame is tracked
  FramePyramid current = preprocess(frame, &r);
  if (!T_world_cur_ || !reference_->valid) {
    initialise(frame, current, &r);
    end_frame(&r);
    return r;
  }
  Verdict v = track(current, frame.timestamp_s, &r);
  if (v.action == Verdict::lose && appearance_ && !keyframes_.empty()) {
    if (std::optional<Verdict> rv = relocalise(frame, current, &r)) v = std::move(*rv);
  }
  if (v.action == Verdict::lose) {
    r.registration = std::move(v.registration);
    lose(&r, v.why);
    end_frame(&r);
    return r;
  }
  // The verdict is final: apply it.
  const SE3 T_prev = *T_world_cur_;
  r.state = v.state;
  r.T_world_camera = v.T_world_cur;
  r.pose_valid = true;
  r.method = v.method;
  r.message = v.why;
  r.registration = std::move(v.registration);
  const bool fuse = v.action == Verdict::integrate &&
                    (config_.integrate_poor || !r.registration || r.registration->status != RegistrationStatus::poor);
  if (fuse) integrate(frame, v.T_world_cur, &r);
  check_colour(current, &r);  // before the raycast takes the frame's intensity for the next reference
  raycast_reference(current, v.T_world_cur, r.integrated, &r);
  // After a loss or a relocalisation the motion spans several frames: no prior for the next one, not a wrong one.
  motion_prior_ = lost_spell_ == 0 && v.state != TrackState::relocalised;
  velocity_ = motion_prior_ ? T_prev.inverse() * v.T_world_cur : SE3();
  velocity_dt_s_ = frame.timestamp_s - last_time_s_;
  T_world_cur_ = v.T_world_cur;
  last_time_s_ = frame.timestamp_s;
  lost_spell_ = 0;
  if (r.integrated) keep_frame(frame, &r);
  if (r.keyframe) query_loop_candidates(frame, &r);
  end_frame(&r);
  return r;
}

// Between this frame and the next: the re-fusion budget, a back-end job when one can start, the backlog.
void Pipeline::end_frame(FrameResult* r) {
  reintegrate(r);
  start_loop_job(r);
  r->refusion_backlog = fused_.pending();
  record_anchor(*r);
}

// Every frame_step-th integrated frame while undecided, as long as the primary reads colour. Once the colour is
// judged unregistered, the depth-only method tracks from the next frame on (and registers keyframe pairs); a
// fallback of the same name would only repeat it.
void Pipeline::check_colour(const FramePyramid& current, FrameResult* r) {
  if (!registration_ || !registration_->reads_colour() || !r->integrated || current.levels.empty() ||
      !colour_check_.wants(r->index))
    return;
  const auto t0 = std::chrono::steady_clock::now();
  r->colour_alignment = estimate_colour_alignment(current.levels[0], config_.colour_check);
  const bool decided = colour_check_.add(*r->colour_alignment, r->index);
  r->ms.track += ms_since(t0);
  if (!decided || colour_check_.verdict() != ColourVerdict::unregistered) return;
  RegistrationOptions o = config_.depth_only_registration_options
                             ? *config_.depth_only_registration_options
                             : pipeline_registration_options(config_.colour_check.depth_only_registration,
                                                             config_.pyramid.levels);
  o.driver.iterations = registration_->options().driver.iterations;
  registration_ = make_registration(config_.colour_check.depth_only_registration, o, make_backend(config_.backend));
  if (wide_)
    wide_ = make_registration(config_.colour_check.depth_only_registration, wide_basin_options(o),
                              make_backend(config_.backend));
  if (fallback_ && fallback_->name() == registration_->name()) fallback_.reset();
}

FramePyramid Pipeline::preprocess(const RgbdFrame& frame, FrameResult* r) const {
  const auto t0 = std::chrono::steady_clock::now();
  FramePyramidOptions po = config_.pyramid;
  po.first_level = config_.tracking_level;
  po.levels = tracking_levels_;
  FramePyramid p = frame_pyramid(device_pyramid_.get(), frame.depth, frame.color, camera_, po);
  r->ms.preprocess = r->ms.undistort + ms_since(t0);
  return p;
}

// Places the first frame (or the first after the map lost its surface) and integrates it. A frame that leaves the
// map without a surface to track against (no valid depth) does not count: the next frame initialises again.
// Mid-sequence the pose stays where tracking left it: ground truth only ever places the very first frame.
void Pipeline::initialise(const RgbdFrame& frame, FramePyramid& current, FrameResult* r) {
  const SE3 T0 = T_world_cur_ ? *T_world_cur_ : frame.T_world_camera_gt.value_or(SE3());
  bool any_depth = false;
  for (const hf_float4& v : current.levels[0].vertices.pixels()) any_depth = any_depth || v.w != 0.0f;
  if (!any_depth) {  // nothing to fuse: the frame is lost without touching the map
    lose(r, "no surface seen yet: the map cannot be initialised from this frame (no valid depth)");
    r->T_world_camera = T0;
    return;
  }
  integrate(frame, T0, r);
  raycast_reference(current, T0, true, r);
  if (!reference_->valid) {
    lose(r, "no surface seen yet: the map cannot be initialised from this frame");
    r->T_world_camera = T0;
    return;
  }
  r->state = TrackState::initialised;
  r->T_world_camera = T0;
  r->pose_valid = true;
  T_world_cur_ = T0;
  last_time_s_ = frame.timestamp_s;
  velocity_ = SE3();
  motion_prior_ = false;
  lost_spell_ = 0;
  keep_frame(frame, r);
  if (r->keyframe) query_loop_candidates(frame, r);
}

Pipeline::Verdict Pipeline::track(const FramePyramid& current, double timestamp_s, FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  SE3 guess = config_.constant_velocity && lost_spell_ == 0 ? velocity_ : SE3();
  if (config_.constant_velocity && config_.velocity_by_time && lost_spell_ == 0 && motion_prior_) {
    // The last motion over this frame's interval; stamps out of order or missing keep the per-frame motion.
    const double ratio = (timestamp_s - last_time_s_) / velocity_dt_s_;
    if (std::isfinite(ratio) && velocity_dt_s_ > 1e-4 && ratio > 0.0 && std::fabs(ratio - 1.0) > 1e-6)
      guess = SE3::exp(std::min(ratio, 5.0) * velocity_.log());
  }
  // Without a measured motion the identity may be far from the truth: the wide basin (wide_basin_without_prior).
  Registration* primary = wide_ && !(motion_prior_ && lost_spell_ == 0) ? wide_.get() : registration_.get();
  std::optional<RegistrationResult> seed;  // seed_registration's estimate on this frame
  bool seeded_guess = false;
  if (seed_) {  // a wide-baseline estimate replaces a motion prior it disagrees with (seed_registration)
    seed = align_to_model(*seed_, current, guess);
    const SE3 d = guess.inverse() * seed->T_ref_cur;
    if (seed->usable() && (d.translation().norm() > config_.seed_min_motion_m ||
                           d.angle_rad() * 180.0 / M_PI > config_.seed_min_motion_deg)) {
      guess = seed->T_ref_cur;
      seeded_guess = true;
      primary = registration_.get();  // the seed's estimate is the prior
    }
  }
  r->wide_basin = primary == wide_.get();
  Verdict v = register_from(*primary, current, guess, timestamp_s, r);
  // A guess that came from the seed already was the wide-baseline start: a retry would repeat it. Without a motion
  // prior an accepted frame is checked against the seed too: from far, the wide basin can settle in a wrong
  // minimum that the map's depth does not refute (a slide along a wall: synthetic room, 8 degrees and 20 cm from
  // the identity, 9 cm off at five times the converged cost); the dense method from the seed's estimate replaces
  // it where it fits the frame better.
  if (failure_seed_ && !seeded_guess && (v.action != Verdict::integrate || r->wide_basin))
    v = retry_from_seed(current, guess, timestamp_s, std::move(v), seed, r);
  r->ms.track = ms_since(t0);
  return v;
}

// The primary from `guess`; where the map does not take its result, the fallback from the same guess.
Pipeline::Verdict Pipeline::register_from(Registration& primary_method, const FramePyramid& current, const SE3& guess,
                                          double timestamp_s, FrameResult* r) {
  const RegistrationResult primary_result = align_to_model(primary_method, current, guess);
  r->term_disagreement = term_disagreement(primary_result);
  Verdict primary = decide(primary_result, current, timestamp_s, registration_->name());
  if (primary.action == Verdict::integrate || !fallback_) return primary;
  Verdict fallback = decide(align_to_model(*fallback_, current, guess), current, timestamp_s,
                            config_.fallback_registration);
  if (fallback.action == Verdict::integrate) {
    fallback.why = registration_->name() + " rejected (" + primary.why + "); " + config_.fallback_registration +
                   " accepted";
    return fallback;
  }
  return primary.action == Verdict::odometry || fallback.action != Verdict::odometry ? primary : fallback;
}

// seed_on_failure: the frame was not integrated from the motion prior. Dense methods fail that way where the
// motion left their basin (15 degrees between frames, or the frame after a lost one, tracked from the identity);
// a method with no basin (sparse: features and RANSAC) estimates the motion once, and the dense methods retry from
// there. The retry replaces the verdict where it does better (integrate over odometry over lose), so a seed can
// only add frames to the map, each passing the same failure policy. seed_registration's estimate of this frame is
// reused where it is the same method.
Pipeline::Verdict Pipeline::retry_from_seed(const FramePyramid& current, const SE3& guess, double timestamp_s,
                                            Verdict failed, const std::optional<RegistrationResult>& seed,
                                            FrameResult* r) {
  r->seeded_on_failure = true;
  const RegistrationResult s = seed && seed_->name() == failure_seed_->name()
                                   ? *seed
                                   : align_to_model(*failure_seed_, current, guess);
  if (const std::optional<std::string> why = implausible(s, timestamp_s)) {
    if (failed.action != Verdict::integrate) failed.why += "; " + failure_seed_->name() + " seed not plausible: " + *why;
    return failed;
  }
  const TermDisagreement kept = r->term_disagreement;
  Verdict retry = register_from(*registration_, current, s.T_ref_cur, timestamp_s, r);
  // integrate over odometry over lose; between two integrated estimates (the cross-check of a frame without a
  // motion prior) the one with the lower cost: the same method on the same frame and reference, so the costs compare.
  const auto rank = [](const Verdict& x) {
    return x.action == Verdict::integrate ? 2 : x.action == Verdict::odometry ? 1 : 0;
  };
  const bool better = rank(retry) > rank(failed) ||
                      (rank(retry) == 2 && rank(failed) == 2 && retry.registration && failed.registration &&
                       retry.registration->final_cost < failed.registration->final_cost);
  if (!better) {
    r->term_disagreement = kept;
    if (failed.action != Verdict::integrate) failed.why += "; from the " + failure_seed_->name() + " seed: " + retry.why;
    return failed;
  }
  r->placed_by_seed = true;
  if (failed.action == Verdict::integrate)
    retry.why = "without a motion prior: the wide basin settled at cost " +
                std::to_string(failed.registration->final_cost) + ", from the " + failure_seed_->name() +
                " seed at " + std::to_string(retry.registration->final_cost);
  else
    retry.why = "from the motion prior: " + failed.why + "; from the " + failure_seed_->name() + " seed: " +
                (retry.why.empty() ? retry.method + " accepted" : retry.why);
  return retry;
}

// Why a registration cannot be the frame's motion before the map is asked (the failure policy's plausibility), or
// nothing when it can.
std::optional<std::string> Pipeline::implausible(const RegistrationResult& reg, double timestamp_s) const {
  if (!reg.usable()) return std::string("registration ") + hf::to_string(reg.status) + ": " + reg.message;
  if (reg.degenerate_dims > config_.max_degenerate_dims)
    return "registration degenerate in " + std::to_string(reg.degenerate_dims) + " directions (at most " +
           std::to_string(config_.max_degenerate_dims) + " accepted)";
  // Plausibility against the sensor clock; a frame rate of 30 Hz when stamps are missing or out of order.
  double dt = timestamp_s - last_time_s_;
  if (!(dt > 1e-6)) dt = 1.0 / 30.0;
  const double speed = reg.T_ref_cur.translation().norm() / dt;
  const double angular = (reg.T_ref_cur.angle_rad() * 180.0 / M_PI) / dt;
  if (speed > config_.max_speed_m_per_s)
    return "implausible motion: " + std::to_string(speed) + " m/s > max_speed_m_per_s " +
           std::to_string(config_.max_speed_m_per_s);
  if (angular > config_.max_angular_speed_deg_per_s)
    return "implausible rotation: " + std::to_string(angular) + " deg/s > max_angular_speed_deg_per_s " +
           std::to_string(config_.max_angular_speed_deg_per_s);
  return std::nullopt;
}

Pipeline::Verdict Pipeline::decide(const RegistrationResult& reg, const FramePyramid& current, double timestamp_s,
                                   const std::string& method) const {
  Verdict v;
  v.registration = reg;
  v.method = method;
  if (std::optional<std::string> why = implausible(reg, timestamp_s)) {
    v.why = std::move(*why);
    return v;
  }
  v.T_world_cur = reference_->T_world_model * reg.T_ref_cur;
  const Consistency cons =
      reference_->stale
          ? volume_consistency(current.levels[0].vertices, grid_, v.T_world_cur)
          : depth_consistency(current.levels[0].vertices, reference_->model.depth, tracking_camera_, reg.T_ref_cur,
                              config_.volume.voxel_m);
  if (cons.sampled > 0 && double(cons.overlap) >= config_.min_overlap * double(cons.sampled) &&
      double(cons.consistent) < config_.min_consistent * double(cons.overlap)) {
    v.why = "depth disagrees with the map: " + std::to_string(cons.consistent) + " of " +
            std::to_string(cons.overlap) + " overlapping samples consistent (min_consistent " +
            std::to_string(config_.min_consistent) + ")";
    // While tracking, the pose keeps moving; after a loss only a consistent frame may end the spell.
    if (lost_spell_ == 0) {
      v.action = Verdict::odometry;
      v.state = TrackState::odometry;
    }
    return v;
  }
  v.action = Verdict::integrate;
  v.state = lost_spell_ > 0 ? TrackState::recovered : TrackState::tracked;
  return v;
}

// Registers the lost frame against the keyframes its appearance retrieves (from the keyframe's own depth and
// colour, identity start), keeps the candidate whose depth agrees best with that keyframe's, and accepts it only
// if the frame's depth agrees with a raycast of the map at the candidate pose.
std::optional<Pipeline::Verdict> Pipeline::relocalise(const RgbdFrame& frame, const FramePyramid& current,
                                                      FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  commit_pending_images();
  Registration& reg_method = fallback_ ? *fallback_ : *registration_;
  const std::vector<AppearanceMatch> matches =
      appearance_->query(frame.color, frame.depth, size_t(config_.relocalisation.candidates));
  std::optional<Verdict> best;
  double best_score = -1.0;
  FramePyramidOptions po = config_.pyramid;
  po.first_level = config_.tracking_level;
  for (const AppearanceMatch& m : matches) {
    if (m.id >= keyframes_.size() || !keyframes_.has_images(m.id)) continue;
    const DepthImage kd = keyframes_.depth(m.id);
    const ColorImage kc = keyframes_.colour(m.id);
    const FramePyramid kp = frame_pyramid(device_pyramid_.get(), kd, kc, camera_, po);
    const RegistrationResult reg = reg_method.align(current, kp, SE3());
    if (!reg.usable() || reg.degenerate_dims > config_.max_degenerate_dims) continue;
    const Consistency c = depth_consistency(current.levels[0].vertices, depth_of(kp.levels[0].vertices),
                                            tracking_camera_, reg.T_ref_cur, config_.volume.voxel_m);
    if (c.sampled == 0 || double(c.overlap) < config_.min_overlap * double(c.sampled)) continue;
    const double score = double(c.consistent) / double(c.overlap);
    if (score < config_.min_consistent || score <= best_score) continue;
    best_score = score;
    Verdict v;
    v.action = Verdict::integrate;
    v.state = TrackState::relocalised;
    v.T_world_cur = keyframes_[m.id].T_world_camera * reg.T_ref_cur;
    v.registration = reg;
    v.method = "relocalisation";
    v.why = "relocalised against keyframe " + std::to_string(m.id) + " (frame " +
            std::to_string(keyframes_[m.id].frame_index) + ")";
    best = std::move(v);
  }
  if (best) {
    // Verification against the map itself: the keyframe may be right and its pose since corrected.
    fusion::RaycastOptions ro = config_.raycast;
    const fusion::RaycastResult model = fusion::raycast(grid_, tracking_camera_, best->T_world_cur, ro);
    const Consistency c = depth_consistency(current.levels[0].vertices, model.depth, tracking_camera_, SE3(),
                                            config_.volume.voxel_m);
    if (c.sampled == 0 || double(c.overlap) < config_.min_overlap * double(c.sampled) ||
        double(c.consistent) < config_.min_consistent * double(c.overlap))
      best.reset();
  }
  r->ms.relocalise = ms_since(t0);
  return best;
}

void Pipeline::integrate(const RgbdFrame& frame, const SE3& T_world_cur, FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
#ifdef HF_HAVE_FUSION_OPENCL
  if (device_map_) {
    if (device_map_stale_) device_map_->load(grid_);
    device_map_stale_ = false;
    device_map_->integrate(frame.depth, frame.color, camera_, T_world_cur, config_.integrate);
    device_map_->read_last_frame_into(grid_);  // the host raycast, re-fusion and meshing read grid_
    r->ms.integrate = ms_since(t0);
    r->integrated = true;
    return;
  }
#endif
  fusion::integrate(grid_, frame.depth, frame.color, camera_, T_world_cur, config_.integrate, &store_);
  if (config_.stream_radius_m > 0)
    fusion::stream_out(grid_, store_, T_world_cur.translation(), config_.stream_radius_m);
  r->ms.integrate = ms_since(t0);
  r->integrated = true;
}

// The frame is kept for re-fusion, anchored to the newest keyframe (itself when it just became one).
void Pipeline::record_anchor(const FrameResult& r) {
  if (keyframes_.empty()) {
    anchors_.push_back({std::string::npos, r.T_world_camera, r.timestamp_s});
    return;
  }
  const size_t k = keyframes_.size() - 1;
  anchors_.push_back({k, keyframes_[k].T_world_camera.inverse() * r.T_world_camera, r.timestamp_s});
}

std::vector<SE3> Pipeline::corrected_trajectory() const {
  std::vector<SE3> out;
  out.reserve(anchors_.size());
  for (const Anchor& a : anchors_)
    out.push_back(a.keyframe == std::string::npos ? a.T_keyframe_frame
                                                  : keyframes_[a.keyframe].T_world_camera * a.T_keyframe_frame);
  return out;
}

void Pipeline::load_map(fusion::VoxelBlockGrid grid, fusion::BlockStore store) {
  if (frames_ > 0) throw Error("load_map: the pipeline has processed frames already; load a map before the first");
  const fusion::VolumeParams& have = config_.volume;
  const fusion::VolumeParams& got = grid.params();
  if (got.voxel_m != have.voxel_m || got.truncation_vox != have.truncation_vox)
    throw Error("load_map: the map has voxels of " + number_for_message(got.voxel_m) + " m and truncation " +
                number_for_message(got.truncation_vox) + " voxels, the configuration " +
                number_for_message(have.voxel_m) + " m and " + number_for_message(have.truncation_vox) +
                " (set volume.voxel_m / truncation_vox to the map's)");
  grid_ = std::move(grid);
  store_ = std::move(store);
  device_map_stale_ = true;  // a device map (backend opencl) loads it before the next integrate
}

Trajectory Pipeline::corrected_stamped_trajectory() const {
  const std::vector<SE3> poses = corrected_trajectory();
  Trajectory out;
  out.reserve(poses.size());
  for (size_t i = 0; i < poses.size(); ++i) out.push_back({anchors_[i].timestamp_s, poses[i]});
  return out;
}

// The new keyframe's appearance matches, retrieved now: the index is this thread's (the back-end gets copies).
void Pipeline::query_loop_candidates(const RgbdFrame& frame, FrameResult* r) {
  if (!loop_closer_ || keyframes_.empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const LoopClosureOptions& lo = config_.loop_closure;
  const size_t k = keyframes_.size() - 1;
  const size_t wanted = size_t(lo.candidates + lo.min_keyframe_gap) * 2;
  loop_matches_[k] = k == 0 ? std::vector<AppearanceMatch>{} : appearance_->query(frame.color, frame.depth, wanted);
  r->ms.loop += ms_since(t0);
}

// A job for the keyframes new since the last one, when none is in flight. Only keyframes whose images are
// committed go (the newest may still be compressing: it goes with the next job), so what a job holds depends on
// the frames processed, never on how fast the compression ran.
void Pipeline::start_loop_job(FrameResult* r) {
  if (!loop_closer_ || loop_job_) return;
  size_t limit = keyframes_.size();
  if (pending_images_ && pending_images_->keyframe) limit = std::min(limit, *pending_images_->keyframe);
  if (keyframes_handed_ >= limit) return;
  const auto t0 = std::chrono::steady_clock::now();
  LoopJob job;
  job.snapshot_frame = frames_;
  job.keyframes.reserve(limit);
  job.has_images.reserve(limit);
  for (size_t i = 0; i < limit; ++i) {
    job.keyframes.push_back(keyframe_metadata(keyframes_[i]));
    job.has_images.push_back(keyframes_.has_images(i));
  }
  job.loops = loops_;
  job.window = window_;
  for (size_t id = keyframes_handed_; id < limit; ++id) {
    LoopJobKeyframe added;
    added.id = id;
    added.images = keyframes_[id].images;
    const auto m = loop_matches_.find(id);
    if (m != loop_matches_.end()) {
      added.matches = std::move(m->second);
      loop_matches_.erase(m);
    }
    job.added.push_back(std::move(added));
  }
  keyframes_handed_ = limit;
  job.method = registration_->name();
  job.method_options = registration_->options();
  job.time_budget = realtime_;

  LoopJobInFlight in_flight;
  in_flight.result = std::make_shared<LoopJobResult>();
  in_flight.apply_at_frame = frames_ + size_t(config_.loop_closure.apply_delay_frames);
  // The task owns the job and writes only the result slot; `done` orders that write before the tracker's read.
  auto task = [closer = loop_closer_.get(), result = in_flight.result, job = std::move(job)]() mutable {
    *result = closer->run(std::move(job));
  };
  if (backend_thread_) {
    in_flight.done = backend_thread_->submit(std::move(task));
  } else {
    std::packaged_task<void()> now(std::move(task));
    in_flight.done = now.get_future();
    now();
  }
  loop_job_ = std::move(in_flight);
  r->ms.loop += ms_since(t0);
}

// Applies the job in flight when it is due (offline: at its frame, waiting for it if it is late; realtime: as
// soon as it is done), or, with `wait`, now.
void Pipeline::finish_loop_job(bool wait, FrameResult* r) {
  if (!loop_job_) return;
  if (!wait) {
    const bool due = realtime_ ? loop_job_->done.wait_for(std::chrono::seconds(0)) == std::future_status::ready
                               : frames_ >= loop_job_->apply_at_frame;
    if (!due) return;
  }
  const auto t0 = std::chrono::steady_clock::now();
  LoopJobInFlight job = std::move(*loop_job_);
  loop_job_.reset();
  job.done.get();  // waits when the back-end is late; rethrows its error
  const double refuse_before = r->ms.reintegrate;
  apply_loop_result(*job.result, r);
  r->ms.loop += ms_since(t0) - (r->ms.reintegrate - refuse_before);  // the re-fusion burst is its own stage
}

void Pipeline::apply_loop_result(const LoopJobResult& res, FrameResult* r) {
  r->loop_applied = true;
  r->backend_job_ms = res.ms;
  for (const LoopJobResult::Odometry& o : res.odometry)
    if (o.id < keyframes_.size()) keyframes_.set_odometry(o.id, o.T_previous_this, o.information);
  loops_ = res.loops;  // only jobs change the loops, and one runs at a time: the list it started from is ours
  window_ = res.window;  // likewise
  window_registrations_ += res.window_registrations;
  if (res.T_world_keyframe.empty() || res.keyframes == 0 || res.keyframes > keyframes_.size()) return;
  // The keyframes made after the snapshot, the current pose and the tracking reference (its maps are in the
  // camera frame) move rigidly with the snapshot's newest keyframe.
  const size_t n = res.keyframes;
  const SE3 correction = res.T_world_keyframe[n - 1] * keyframes_[n - 1].T_world_camera.inverse();
  for (size_t i = 0; i < n; ++i) keyframes_.set_pose(i, res.T_world_keyframe[i]);
  for (size_t i = n; i < keyframes_.size(); ++i) keyframes_.set_pose(i, correction * keyframes_[i].T_world_camera);
  if (T_world_cur_) T_world_cur_ = correction * *T_world_cur_;
  reference_->T_world_model = correction * reference_->T_world_model;
  loops_closed_ += res.loops_closed;
  window_solves_ += res.window_solves;
  r->loop_closed = res.loops_closed > 0;
  ++corrections_;
  if (!config_.reintegration.enabled) return;
  fused_.schedule(keyframes_, camera_, config_.volume.voxel_m);
  // A window solve alone moves the keyframes by a local adjustment: its re-fusions go at the per-frame rate.
  if (res.loops_closed == 0) return;
  // The most-displaced frames are the ones just before the loop, whose surfaces the camera sees now: until they
  // are re-fused, the next frames track against them at their old poses and snap back by the correction.
  // Realtime mode has only its per-frame budget. Offline, frames_after_loop re-fusions are owed from this frame
  // on, at most frames_after_loop_per_step a frame (Pipeline::reintegrate), so the loop frame does not stall; a
  // later loop adds its own to what is still owed (bounded: the queue it re-fuses from holds the stored frames).
  if (realtime_) return;
  loop_refusions_owed_ += size_t(config_.reintegration.frames_after_loop);
  pay_loop_refusions(r);
}

// Up to frames_after_loop_per_step of the re-fusions a loop left owed (offline), most-displaced first.
void Pipeline::pay_loop_refusions(FrameResult* r) {
  if (loop_refusions_owed_ == 0) return;
  if (fused_.pending() == 0) {
    loop_refusions_owed_ = 0;
    return;
  }
  loop_refusions_paid_at_ = frames_;
  const auto t0 = std::chrono::steady_clock::now();
  const size_t n = std::min(loop_refusions_owed_, size_t(config_.reintegration.frames_after_loop_per_step));
  const size_t done = fused_.step(n, keyframes_, grid_, camera_, config_.integrate, &store_);
  loop_refusions_owed_ = fused_.pending() == 0 ? 0 : loop_refusions_owed_ - n;
  r->reintegrated += done;
  r->ms.reintegrate += ms_since(t0);
  if (done > 0) device_map_stale_ = true;
}

// Solves the keyframe graph (finish(true)); on success every keyframe takes its solution. False when the solve
// failed.
bool Pipeline::apply_graph(const PoseGraphOptions& options) {
  const PoseGraph g =
      keyframe_graph(keyframes_, loops_, window_, config_.loop_closure.tracking_information_scale_in_graph());
  const PoseGraphResult res = g.optimize(options);
  if (!res.ok()) return false;
  for (size_t i = 0; i < keyframes_.size() && i < res.T_world_node.size(); ++i)
    keyframes_.set_pose(i, res.T_world_node[i]);
  return true;
}

// The re-fusion budget between two frames: frames_per_step re-fusions offline, budget_ms_per_frame realtime.
void Pipeline::reintegrate(FrameResult* r) {
  if (!config_.reintegration.enabled || fused_.pending() == 0) return;
  if (!realtime_ && loop_refusions_paid_at_ != frames_) pay_loop_refusions(r);  // once per frame
  if (fused_.pending() == 0) return;
  const auto t0 = std::chrono::steady_clock::now();
  size_t done = 0;
  if (realtime_) {
    while (fused_.pending() > 0 && ms_since(t0) < config_.reintegration.budget_ms_per_frame)
      done += fused_.step(1, keyframes_, grid_, camera_, config_.integrate, &store_);
  } else {
    done = fused_.step(size_t(config_.reintegration.frames_per_step), keyframes_, grid_, camera_, config_.integrate,
                       &store_);
  }
  r->reintegrated += done;
  r->ms.reintegrate += ms_since(t0);
  if (done > 0) device_map_stale_ = true;
}

double Pipeline::finish(bool global) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!registration_) return 0.0;
  device_map_stale_ = true;
  commit_pending_images();
  // The job in flight, then one for the keyframes it did not see (every image is committed now).
  FrameResult scratch;
  finish_loop_job(true, &scratch);
  start_loop_job(&scratch);
  finish_loop_job(true, &scratch);
  if (global && keyframes_.size() > 1) {
    PoseGraphOptions o = config_.loop_closure.graph;
    o.time_budget_ms = std::max(o.time_budget_ms, 10000.0);
    o.max_iterations = std::max(o.max_iterations, 500);
    // Without a loop the graph is a chain: its solution would only swap the model-tracked poses for the chained
    // keyframe-to-keyframe registrations (each from two frames, not the whole map), so nothing global is solved.
    if (!loops_.empty() || !window_.empty()) apply_graph(o);
    if (config_.reintegration.enabled) fused_.refuse_all(keyframes_, grid_, camera_, config_.integrate, &store_);
  } else if (config_.reintegration.enabled) {
    fused_.schedule(keyframes_, camera_, config_.volume.voxel_m);
    fused_.step(fused_.pending(), keyframes_, grid_, camera_, config_.integrate, &store_);
  }
  return ms_since(t0);
}

// The model maps at the new pose become the reference, with this frame's intensity as the photometric reference.
// A primary method that aligns to the map itself needs no raycast: the reference is then the pose alone, and its
// maps are cast only if another method asks for them (ensure_reference_maps).
void Pipeline::raycast_reference(FramePyramid& current, const SE3& T_world_cur, bool integrated, FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  if (registration_ && registration_->aligns_to_volume()) {
    reference_->T_world_model = T_world_cur;
    reference_->stale = true;
    // Kept for a photometric fallback: ensure_reference_maps puts it on the maps it casts.
    reference_->frame_intensity.levels.resize(size_t(current.num_levels()));
    take_intensity(current, &reference_->frame_intensity);
    reference_->valid = grid_.block_count() > 0;
    r->ms.raycast = ms_since(t0);
    return;
  }
  // The frame just integrated from this pose tells each ray where the surface is (fusion/raycast.h depth_hint):
  // its depth at the tracking resolution, from the pyramid's vertices. Where the frame has no depth, the last
  // model raycast moved to this pose (fusion::forward_project_depth) does: those rays would otherwise march
  // their tile's whole depth range. A frame that was not integrated hints nothing about the model.
  fusion::RaycastOptions ro = config_.raycast;
  DepthImage hint;
  if (!current.levels.empty()) {
    const VertexMap& v = current.levels[0].vertices;
    if (reference_->valid && config_.model_hint)
      fusion::forward_project_depth(reference_->model.vertices, T_world_cur.inverse() * reference_->T_world_model,
                                    tracking_camera_, &hint);
    else
      hint = DepthImage(v.width(), v.height(), 0.0f);
    if (integrated)
      for (int y = 0; y < v.height(); ++y)
        for (int x = 0; x < v.width(); ++x)
          if (v(x, y).w != 0.0f) hint(x, y) = v(x, y).z;
    ro.depth_hint = &hint;
  }
  if (config_.tracking_raycast == "sampled" && !current.levels.empty() && config_.registration_options) {
    // Only the rays whose vertices the next frame's selected rows will land on (this frame's selection, grown).
    const PixelSelectionOptions& selection = config_.registration_options->driver.row_selection;
    const Image<std::uint8_t> rays = select_pixels(current.levels[0], selection);
    fusion::raycast_sampled(grid_, tracking_camera_, T_world_cur, ro,
                            fusion::dilate_rays(rays, config_.tracking_raycast_dilate_px), &reference_->model);
  } else {
    model_raycast(T_world_cur, ro);
  }
  reference_->T_world_model = T_world_cur;
  reference_->pyramid =
      model_pyramid(device_pyramid_.get(), reference_->model, tracking_camera_, tracking_levels_);
  take_intensity(current, &reference_->pyramid);
  reference_->valid = reference_->model.hit_count > 0;
  reference_->stale = false;
  r->ms.raycast = ms_since(t0);
}

// The tracking raycast into reference_->model: on the device map where there is one (DeviceVoxelGrid::raycast, the
// same march and options; the map loaded again first when the host changed it), else on the host grid.
void Pipeline::model_raycast(const SE3& T_world_camera, const fusion::RaycastOptions& options) {
#ifdef HF_HAVE_FUSION_OPENCL
  if (device_map_) {
    if (device_map_stale_) device_map_->load(grid_);
    device_map_stale_ = false;
    device_map_->raycast(tracking_camera_, T_world_camera, options, &reference_->model);
    return;
  }
#endif
  fusion::raycast(grid_, tracking_camera_, T_world_camera, options, &reference_->model);
}

void Pipeline::ensure_reference_maps() {
  if (!reference_->stale) return;
  model_raycast(reference_->T_world_model, config_.raycast);
  reference_->pyramid =
      model_pyramid(device_pyramid_.get(), reference_->model, tracking_camera_, tracking_levels_);
  take_intensity(reference_->frame_intensity, &reference_->pyramid);
  reference_->stale = false;
}

// A method that aligns to the map gets it (and the reference pose) for this one call only: the same object also
// registers keyframe pairs, pyramid to pyramid. Any other method gets the reference maps, cast now if stale.
RegistrationResult Pipeline::align_to_model(Registration& method, const FramePyramid& current, const SE3& guess) {
  if (!method.aligns_to_volume()) {
    ensure_reference_maps();
    return method.align(current, reference_->pyramid, guess);
  }
  method.set_volume(&grid_, reference_->T_world_model);
  DeviceCopies map_copies;  // the device map as grid_'s copy for this call (a device backend reads it in place)
#ifdef HF_HAVE_FUSION_OPENCL
  if (device_map_) {
    if (device_map_stale_) device_map_->load(grid_);
    device_map_stale_ = false;
    map_copies = device_map_->publish_map(grid_);
  }
#endif
  RegistrationResult result = method.align(current, FramePyramid{}, guess);
  method.set_volume(nullptr, SE3());
  return result;
}

// An integrated frame is compressed once, for the re-fusion store and, when it is due, as a keyframe (which is
// then the anchor it is stored with).
void Pipeline::keep_frame(const RgbdFrame& frame, FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  commit_pending_images();
  const bool keyframe = keyframes_.wants_keyframe(r->T_world_camera, frame.index);
  if (!keyframe && !config_.reintegration.enabled) {
    r->ms.keyframe = ms_since(t0);
    return;
  }
  PendingImages p;
  p.correction = corrections_;
  p.images = std::async(std::launch::async, [depth = frame.depth, colour = frame.color,
                                             quality = config_.keyframes.jpeg_quality, params = config_.integrate] {
    KeptImages kept;
    kept.images = CompressedRgbd::encode(depth, colour, quality);
    for (const float d : depth.pixels())  // what integrate() took: finite, within [min_depth_m, max_depth_m]
      if (d >= params.min_depth_m && d <= params.max_depth_m && d > kept.max_depth_m) kept.max_depth_m = d;
    return kept;
  });
  if (keyframe) {
    const Matrix6d info = r->registration ? r->registration->information : Matrix6d::Zero();
    p.keyframe = keyframes_.add(frame.index, frame.timestamp_s, r->T_world_camera, info, CompressedRgbd{});
    if (appearance_) appearance_->add(*p.keyframe, frame.color, frame.depth);
    r->keyframe = true;
  }
  if (!keyframes_.empty()) {
    p.frame_index = frame.index;
    p.anchor = keyframes_.size() - 1;
    p.T_world_anchor = keyframes_[p.anchor].T_world_camera;
    p.T_world_frame = r->T_world_camera;
  }
  pending_images_ = std::move(p);
  r->ms.keyframe = ms_since(t0);
}

// Waits for the last kept frame's compression and hands the images to its keyframe and the re-fusion store.
void Pipeline::commit_pending_images() {
  if (!pending_images_) return;
  PendingImages p = std::move(*pending_images_);
  pending_images_.reset();
  KeptImages kept = p.images.get();
  const bool refuse = config_.reintegration.enabled && !keyframes_.empty();
  if (p.keyframe) keyframes_.set_images(*p.keyframe, refuse ? kept.images : std::move(kept.images));
  if (!refuse) return;
  // Voxels up to a truncation band beyond the farthest depth were updated.
  fused_.add(p.frame_index, p.anchor, p.T_world_anchor, p.T_world_frame, std::move(kept.images),
             double(kept.max_depth_m) + grid_.params().truncation_m());
  // A loop result applied since the frame was kept moved its anchor: it joins the re-fusion queue.
  if (p.correction != corrections_) fused_.schedule(keyframes_, camera_, config_.volume.voxel_m);
}

void Pipeline::lose(FrameResult* r, std::string why) {
  ++lost_;
  ++lost_spell_;
  r->state = TrackState::lost;
  r->pose_valid = false;
  r->T_world_camera = T_world_cur_.value_or(SE3());
  r->message = std::move(why);
}

TriangleMesh Pipeline::extract_mesh() const {
  fusion::MeshOptions options;
  return fusion::extract_mesh(grid_, store_, options);
}

ColorImage Pipeline::render(const SE3& T_world_camera) const {
  fusion::RaycastOptions options = config_.raycast;
  options.shade = true;
  options.color = true;  // the tracking raycast's options leave it off
  return fusion::colored_shading(fusion::raycast(grid_, camera_, T_world_camera, options));
}

std::map<std::string, std::string> Pipeline::stage_devices() const {
  std::map<std::string, std::string> d{{"preprocess", "cpu"}, {"registration", "cpu"}, {"integrate", "cpu"},
                                       {"raycast", "cpu"}};
#ifdef HF_HAVE_FUSION_OPENCL
  if (device_map_) d["integrate"] = device_map_->device_name();
  // The tracking raycast (the sampled one, issue 19, stays on the host).
  if (device_map_ && config_.tracking_raycast != "sampled") d["raycast"] = device_map_->device_name();
  if (device_pyramid_) d["preprocess"] = device_pyramid_->device_name();
  if (config_.backend == "opencl" && registration_) {
    const auto context = opencl::Context::shared();  // the backends' (they hold it)
    d["registration"] = context->info().platform_name + " / " + context->info().device_name;  // the reductions
  }
#else
  if (config_.backend == "opencl" && registration_) d["registration"] = "opencl";
#endif
  return d;
}

}  // namespace hf::slam
