#include "slam/pipeline.h"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "core/kernels/image_kernels.h"
#include "fusion/mesh.h"
#include "fusion/raycast_sampled.h"
#include "registration/pixel_selection.h"
#ifdef HF_HAVE_FUSION_OPENCL
#include "fusion/opencl/device_voxel_grid.h"
#include "registration/opencl/device_pyramid.h"
#include "core/opencl/opencl_context.h"
#include "core/timing.h"
#endif

namespace hf::slam {
namespace {

// Share of the frame's depth that agrees with a reference depth image where it lands (see
// PipelineConfig::min_consistent): (pixels sampled, pixels landing on the reference, pixels agreeing).
struct Consistency {
  long sampled = 0, overlap = 0, consistent = 0;
};

// Every 4th pixel of `current` in x and y, moved by T (float): agree(p, z_cur) returns -1 (no overlap), 0 or 1.
template <class Agree>
Consistency sample_consistency(const VertexMap& current, const SE3& T, Agree agree) {
  const Eigen::Matrix3f R = T.rotation().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  Consistency c;
  constexpr int kStride = 4;
  for (int y = kStride / 2; y < current.height(); y += kStride) {
    for (int x = kStride / 2; x < current.width(); x += kStride) {
      const hf_float4& v = current(x, y);
      if (v.w == 0.0f) continue;
      ++c.sampled;
      const int a = agree(Eigen::Vector3f(R * Eigen::Vector3f(v.x, v.y, v.z) + t), v.z);
      if (a < 0) continue;
      ++c.overlap;
      c.consistent += a;
    }
  }
  return c;
}

Consistency depth_consistency(const VertexMap& current, const DepthImage& reference_depth, const PinholeCamera& cam,
                              const SE3& T_ref_cur, double voxel_m) {
  return sample_consistency(current, T_ref_cur, [&](const Eigen::Vector3f& p, float) {
    if (!(p.z() > 0.0f)) return -1;
    const Eigen::Vector2d px = cam.project(p.cast<double>());
    const int u = int(std::lround(px.x())), w = int(std::lround(px.y()));
    if (u < 0 || w < 0 || u >= cam.width || w >= cam.height) return -1;
    const float d_ref = reference_depth(u, w);
    if (!(d_ref > 0.0f)) return -1;
    return int(std::abs(d_ref - p.z()) <= 3.0f * hf_kinect_axial_sigma_m(p.z()) + float(voxel_m));
  });
}

// depth_consistency's question asked of the map itself, for a primary method that aligns to the volume (no
// tracking raycast to compare with): a sample overlaps where the TSDF around its world point is observed, and
// agrees where its distance to the surface there is within the same noise bound.
Consistency volume_consistency(const VertexMap& current, const fusion::VoxelBlockGrid& grid,
                               const SE3& T_world_cur) {
  const float inv_voxel = float(1.0 / grid.params().voxel_m), mu = float(grid.params().truncation_m());
  fusion::VolumeSampler sampler(grid, 0.0f, false);
  return sample_consistency(current, T_world_cur, [&](const Eigen::Vector3f& p, float z_cur) {
    float s = 0.0f;
    if (!sampler.sdf(p * inv_voxel - Eigen::Vector3f::Constant(0.5f), &s)) return -1;
    return int(std::abs(s * mu) <= 3.0f * hf_kinect_axial_sigma_m(z_cur) + 1.0f / inv_voxel);
  });
}

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

Pipeline::Pipeline(const PipelineConfig& config, const PinholeCamera& camera)
    : config_(config), camera_(camera), tracking_camera_(camera.scaled(config.tracking_level)),
      grid_((config.validate(), config.volume)),
      colour_check_(config.colour_check), reference_(std::make_unique<Reference>()), keyframes_(config.keyframes),
      fused_(config.reintegration) {
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
  if (!config_.fallback_registration.empty() && config_.fallback_registration != config_.registration) {
    RegistrationOptions fo = default_registration_options(config_.fallback_registration);
    fo.driver.iterations = iterations;
    fallback_ = make_registration(config_.fallback_registration, fo, make_backend(config_.backend));
  }
  if (!config_.seed_registration.empty()) {
    RegistrationOptions so = default_registration_options(config_.seed_registration);
    seed_ = make_registration(config_.seed_registration, so, make_backend(config_.backend));
  }
  if (config_.relocalisation.enabled)
    appearance_ = make_appearance_index(config_.relocalisation.appearance.empty()
                                            ? default_appearance_index_name()
                                            : config_.relocalisation.appearance);
}

Pipeline::~Pipeline() = default;

FrameResult Pipeline::process(const RgbdFrame& frame) {
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

  FramePyramid current = preprocess(frame, &r);
  if (!T_world_cur_ || !reference_->valid) {
    initialise(frame, current, &r);
    record_anchor(r);
    return r;
  }
  Verdict v = track(current, frame.timestamp_s, &r);
  if (v.action == Verdict::lose && appearance_ && !keyframes_.empty()) {
    if (std::optional<Verdict> rv = relocalise(frame, current, &r)) v = std::move(*rv);
  }
  if (v.action == Verdict::lose) {
    r.registration = std::move(v.registration);
    lose(&r, v.why);
    reintegrate(&r);
    record_anchor(r);
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
  velocity_ = (lost_spell_ > 0 || v.state == TrackState::relocalised) ? SE3() : T_prev.inverse() * v.T_world_cur;
  T_world_cur_ = v.T_world_cur;
  last_time_s_ = frame.timestamp_s;
  lost_spell_ = 0;
  if (r.integrated) keep_frame(frame, &r);
  if (r.keyframe) close_loops(frame, &r);
  reintegrate(&r);
  record_anchor(r);
  return r;
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
  RegistrationOptions o = pipeline_registration_options(config_.colour_check.depth_only_registration);
  o.driver.iterations = registration_->options().driver.iterations;
  registration_ = make_registration(config_.colour_check.depth_only_registration, o, make_backend(config_.backend));
  if (fallback_ && fallback_->name() == registration_->name()) fallback_.reset();
}

FramePyramid Pipeline::preprocess(const RgbdFrame& frame, FrameResult* r) const {
  const auto t0 = std::chrono::steady_clock::now();
  FramePyramidOptions po = config_.pyramid;
  po.first_level = config_.tracking_level;
  FramePyramid p = frame_pyramid(device_pyramid_.get(), frame.depth, frame.color, camera_, po);
  r->ms.preprocess = ms_since(t0);
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
  lost_spell_ = 0;
  keep_frame(frame, r);
  if (r->keyframe) close_loops(frame, r);
}

Pipeline::Verdict Pipeline::track(const FramePyramid& current, double timestamp_s, FrameResult* r) {
  const auto t0 = std::chrono::steady_clock::now();
  SE3 guess = config_.constant_velocity && lost_spell_ == 0 ? velocity_ : SE3();
  if (seed_) {  // a wide-baseline estimate replaces a motion prior it disagrees with (seed_registration)
    const RegistrationResult seed = align_to_model(*seed_, current, guess);
    const SE3 d = guess.inverse() * seed.T_ref_cur;
    if (seed.usable() && (d.translation().norm() > config_.seed_min_motion_m ||
                          d.angle_rad() * 180.0 / M_PI > config_.seed_min_motion_deg))
      guess = seed.T_ref_cur;
  }
  const RegistrationResult primary_result = align_to_model(*registration_, current, guess);
  r->term_disagreement = term_disagreement(primary_result);
  Verdict primary = decide(primary_result, current, timestamp_s, registration_->name());
  if (primary.action == Verdict::integrate || !fallback_) {
    r->ms.track = ms_since(t0);
    return primary;
  }
  Verdict fallback = decide(align_to_model(*fallback_, current, guess), current, timestamp_s,
                            config_.fallback_registration);
  r->ms.track = ms_since(t0);
  if (fallback.action == Verdict::integrate) {
    fallback.why = registration_->name() + " rejected (" + primary.why + "); " + config_.fallback_registration +
                   " accepted";
    return fallback;
  }
  return primary.action == Verdict::odometry || fallback.action != Verdict::odometry ? primary : fallback;
}

Pipeline::Verdict Pipeline::decide(const RegistrationResult& reg, const FramePyramid& current, double timestamp_s,
                                   const std::string& method) const {
  Verdict v;
  v.registration = reg;
  v.method = method;
  if (!reg.usable()) {
    v.why = std::string("registration ") + hf::to_string(reg.status) + ": " + reg.message;
    return v;
  }
  if (reg.degenerate_dims > config_.max_degenerate_dims) {
    v.why = "registration degenerate in " + std::to_string(reg.degenerate_dims) + " directions (at most " +
            std::to_string(config_.max_degenerate_dims) + " accepted)";
    return v;
  }
  // Plausibility against the sensor clock; a frame rate of 30 Hz when stamps are missing or out of order.
  double dt = timestamp_s - last_time_s_;
  if (!(dt > 1e-6)) dt = 1.0 / 30.0;
  const double speed = reg.T_ref_cur.translation().norm() / dt;
  const double angular = (reg.T_ref_cur.angle_rad() * 180.0 / M_PI) / dt;
  if (speed > config_.max_speed_m_per_s) {
    v.why = "implausible motion: " + std::to_string(speed) + " m/s > max_speed_m_per_s " +
            std::to_string(config_.max_speed_m_per_s);
    return v;
  }
  if (angular > config_.max_angular_speed_deg_per_s) {
    v.why = "implausible rotation: " + std::to_string(angular) + " deg/s > max_angular_speed_deg_per_s " +
            std::to_string(config_.max_angular_speed_deg_per_s);
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
    anchors_.push_back({std::string::npos, r.T_world_camera});
    return;
  }
  const size_t k = keyframes_.size() - 1;
  anchors_.push_back({k, keyframes_[k].T_world_camera.inverse() * r.T_world_camera});
}

std::vector<SE3> Pipeline::corrected_trajectory() const {
  std::vector<SE3> out;
  out.reserve(anchors_.size());
  for (const Anchor& a : anchors_)
    out.push_back(a.keyframe == std::string::npos ? a.T_keyframe_frame
                                                  : keyframes_[a.keyframe].T_world_camera * a.T_keyframe_frame);
  return out;
}

// Registers the new keyframe against its loop candidates from the relative pose their current poses imply; the
// first verified one becomes a loop edge and the graph is solved.
void Pipeline::close_loops(const RgbdFrame& frame, FrameResult* r) {
  if (!config_.loop_closure.enabled || !appearance_ || keyframes_.empty()) return;
  const auto t0 = std::chrono::steady_clock::now();
  const LoopClosureOptions& lo = config_.loop_closure;
  const size_t k = keyframes_.size() - 1;
  FramePyramidOptions po = config_.pyramid;
  po.first_level = config_.tracking_level;
  FramePyramid kp = frame_pyramid(device_pyramid_.get(), frame.depth, frame.color, camera_, po);
  measure_odometry_edge(kp);
  std::vector<size_t> candidates;
  if (k > 0) {
    const std::vector<AppearanceMatch> matches =
        appearance_->query(frame.color, frame.depth, size_t(lo.candidates + lo.min_keyframe_gap) * 2);
    candidates = loop_candidates(keyframes_, k, matches, lo);
  }
  if (candidates.empty()) {
    keyframe_pyramid_ = std::move(kp);
    r->ms.loop = ms_since(t0);
    return;
  }
  // The primary method: keyframe pairs often see one wall and a floor, which leaves ICP alone degenerate.
  Registration& verifier = *registration_;
  size_t added = 0;
  for (size_t c : candidates) {
    const DepthImage cd = keyframes_.depth(c);
    const ColorImage cc = keyframes_.colour(c);
    const FramePyramid cp = frame_pyramid(device_pyramid_.get(), cd, cc, camera_, po);
    const SE3 guess = keyframes_[c].T_world_camera.inverse() * keyframes_[k].T_world_camera;
    const std::optional<RegistrationResult> reg = register_keyframes(verifier, kp, cp, guess);
    if (!reg) continue;
    loops_.push_back({c, k, reg->T_ref_cur, reg->information});
    ++added;
  }
  keyframe_pyramid_ = std::move(kp);
  double refuse_ms = 0.0;
  if (added > 0 && apply_graph(lo.graph, added)) {
    r->loop_closed = true;
    ++loops_closed_;
    // The tracking reference keeps its maps (camera frame) and moves with the current keyframe.
    const SE3 T_new = keyframes_[k].T_world_camera;
    T_world_cur_ = T_new;
    reference_->T_world_model = T_new;
    commit_pending_images();  // the frame still being compressed is re-fused with the others
    if (config_.reintegration.enabled) {
      fused_.schedule(keyframes_);
      const auto t1 = std::chrono::steady_clock::now();
      r->reintegrated += fused_.step(size_t(config_.reintegration.frames_after_loop), keyframes_, grid_, camera_,
                                     config_.integrate, &store_);
      refuse_ms = ms_since(t1);
      r->ms.reintegrate += refuse_ms;  // its own stage, not the loop's
    }
  }
  r->ms.loop = ms_since(t0) - refuse_ms;
}

// The newest keyframe registered against the previous one (their own images, the tracked relative pose as the
// guess). Kept as the odometry edge only when the registration is good and the two depths agree; otherwise the
// graph keeps the tracked relative pose (after a relocalisation the previous keyframe may be out of sight).
void Pipeline::measure_odometry_edge(const FramePyramid& keyframe) {
  const size_t k = keyframes_.size() - 1;
  if (k == 0 || !keyframe_pyramid_ || keyframe_pyramid_->num_levels() == 0) return;
  const std::optional<RegistrationResult> reg =
      register_keyframes(*registration_, keyframe, *keyframe_pyramid_, keyframes_[k].T_previous_this);
  if (!reg || reg->degenerate_dims > 0) return;
  keyframes_.set_odometry(k, reg->T_ref_cur, reg->information);
}

// One keyframe pair registered and verified as loop closure verifies (loop_closure.min_inlier_ratio and
// min_consistent): the result when the registration is good and the depths agree where they overlap.
std::optional<RegistrationResult> Pipeline::register_keyframes(Registration& method, const FramePyramid& current,
                                                               const FramePyramid& reference, const SE3& guess) const {
  const LoopClosureOptions& lo = config_.loop_closure;
  RegistrationResult reg = method.align(current, reference, guess);
  if (reg.status != RegistrationStatus::good || reg.inlier_ratio < lo.min_inlier_ratio) return std::nullopt;
  const Consistency cons = depth_consistency(current.levels[0].vertices, depth_of(reference.levels[0].vertices),
                                             tracking_camera_, reg.T_ref_cur, config_.volume.voxel_m);
  if (cons.overlap == 0 || double(cons.consistent) < lo.min_consistent * double(cons.overlap)) return std::nullopt;
  return reg;
}

// Solves the keyframe graph; on success every keyframe takes its solution. The newest `new_loops` loops are
// checked by the graph's consistency test: those it rejects are dropped, and when it rejects all of them nothing
// moves (false). False too when the solve failed.
bool Pipeline::apply_graph(const PoseGraphOptions& options, size_t new_loops) {
  const PoseGraph g = keyframe_graph(keyframes_, loops_);
  const PoseGraphResult res = g.optimize(options);
  if (!res.ok()) return false;
  new_loops = std::min(new_loops, loops_.size());
  if (new_loops > 0 && res.loop_accepted.size() == loops_.size()) {
    const size_t first = loops_.size() - new_loops;
    std::vector<LoopEdge> kept(loops_.begin(), loops_.begin() + std::ptrdiff_t(first));
    for (size_t i = first; i < loops_.size(); ++i)
      if (res.loop_accepted[i]) kept.push_back(loops_[i]);
    const bool any = kept.size() > first;
    loops_ = std::move(kept);
    if (!any) return false;
  }
  for (size_t i = 0; i < keyframes_.size() && i < res.T_world_node.size(); ++i)
    keyframes_.set_pose(i, res.T_world_node[i]);
  return true;
}

void Pipeline::reintegrate(FrameResult* r) {
  if (!config_.reintegration.enabled || fused_.pending() == 0) return;
  const auto t0 = std::chrono::steady_clock::now();
  r->reintegrated += fused_.step(size_t(config_.reintegration.frames_per_step), keyframes_, grid_, camera_,
                                config_.integrate, &store_);
  r->ms.reintegrate += ms_since(t0);
  if (r->reintegrated > 0) device_map_stale_ = true;  // also the loop's burst (close_loops runs just before)
}

double Pipeline::finish(bool global) {
  const auto t0 = std::chrono::steady_clock::now();
  if (!registration_) return 0.0;
  device_map_stale_ = true;
  commit_pending_images();
  if (global && keyframes_.size() > 1) {
    PoseGraphOptions o = config_.loop_closure.graph;
    o.time_budget_ms = std::max(o.time_budget_ms, 10000.0);
    o.max_iterations = std::max(o.max_iterations, 500);
    // Without a loop the graph is a chain: its solution would only swap the model-tracked poses for the chained
    // keyframe-to-keyframe registrations (each from two frames, not the whole map), so nothing global is solved.
    if (!loops_.empty()) apply_graph(o);
    if (config_.reintegration.enabled) fused_.refuse_all(keyframes_, grid_, camera_, config_.integrate, &store_);
  } else if (config_.reintegration.enabled) {
    fused_.schedule(keyframes_);
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
      model_pyramid(device_pyramid_.get(), reference_->model, tracking_camera_, config_.pyramid.levels);
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
      model_pyramid(device_pyramid_.get(), reference_->model, tracking_camera_, config_.pyramid.levels);
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
  p.images = std::async(std::launch::async, [depth = frame.depth, colour = frame.color,
                                             quality = config_.keyframes.jpeg_quality] {
    return CompressedRgbd::encode(depth, colour, quality);
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
  CompressedRgbd images = p.images.get();
  const bool refuse = config_.reintegration.enabled && !keyframes_.empty();
  if (p.keyframe) keyframes_.set_images(*p.keyframe, refuse ? images : std::move(images));
  if (refuse) fused_.add(p.frame_index, p.anchor, p.T_world_anchor, p.T_world_frame, std::move(images));
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
  return fusion::raycast(grid_, camera_, T_world_camera, options).shaded;
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
