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

namespace hf::slam {
namespace {

double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

// Share of the frame's depth that agrees with the model depth where it lands (see PipelineConfig::min_consistent):
// (pixels sampled, pixels landing on the model, pixels agreeing).
struct Consistency {
  long sampled = 0, overlap = 0, consistent = 0;
};

Consistency depth_consistency(const VertexMap& current, const fusion::RaycastResult& model, const PinholeCamera& cam,
                              const SE3& T_ref_cur, double voxel_m) {
  const Eigen::Matrix3f R = T_ref_cur.rotation().cast<float>();
  const Eigen::Vector3f t = T_ref_cur.translation().cast<float>();
  Consistency c;
  constexpr int kStride = 4;
  for (int y = kStride / 2; y < current.height(); y += kStride) {
    for (int x = kStride / 2; x < current.width(); x += kStride) {
      const hf_float4& v = current(x, y);
      if (v.w == 0.0f) continue;
      ++c.sampled;
      const Eigen::Vector3f p = R * Eigen::Vector3f(v.x, v.y, v.z) + t;
      if (!(p.z() > 0.0f)) continue;
      const Eigen::Vector2d px = cam.project(p.cast<double>());
      const int u = int(std::lround(px.x())), w = int(std::lround(px.y()));
      if (u < 0 || w < 0 || u >= cam.width || w >= cam.height) continue;
      const float d_model = model.depth(u, w);
      if (!(d_model > 0.0f)) continue;
      ++c.overlap;
      c.consistent += std::abs(d_model - p.z()) <= 3.0f * hf_kinect_axial_sigma_m(p.z()) + float(voxel_m);
    }
  }
  return c;
}

}  // namespace

const char* to_string(TrackState state) {
  switch (state) {
    case TrackState::initialised: return "initialised";
    case TrackState::tracked: return "tracked";
    case TrackState::recovered: return "recovered";
    case TrackState::lost: return "lost";
    case TrackState::groundtruth: return "groundtruth";
  }
  return "?";
}

// --- The pipeline -----------------------------------------------------------------------------------------------

// Everything tracking aligns against, all in the camera frame of the last good pose.
struct Pipeline::Reference {
  fusion::RaycastResult model;   // raycast of the map at the last good pose
  SE3 T_world_model;             // that pose
  FramePyramid pyramid;          // model vertices/normals per level + the last good frame's intensity/gradients
  bool valid = false;
};

Pipeline::Pipeline(const PipelineConfig& config, const PinholeCamera& camera)
    : config_(config), camera_(camera), tracking_camera_(camera.scaled(config.tracking_level)),
      grid_((config.validate(), config.volume)),
      reference_(std::make_unique<Reference>()) {
  if (config_.registration != "groundtruth") {
    RegistrationOptions options = effective_registration_options(config_);
    if (int(options.iterations.size()) > config_.pyramid.levels)
      options.iterations.resize(size_t(config_.pyramid.levels));
    config_.registration_options = options;
    registration_ = make_registration(config_.registration, options, make_backend(config_.backend));
  }
}

Pipeline::~Pipeline() = default;

FrameResult Pipeline::process(const RgbdFrame& frame) {
  if (frame.depth.width() != camera_.width || frame.depth.height() != camera_.height)
    throw Error((frame.depth_file.empty() ? "frame " + std::to_string(frame.index) : frame.depth_file) +
                ": depth is " + std::to_string(frame.depth.width()) + "x" + std::to_string(frame.depth.height()) +
                ", camera is " + std::to_string(camera_.width) + "x" + std::to_string(camera_.height));
  const bool has_color = !frame.color.empty();
  if (has_color && (frame.color.width() != camera_.width || frame.color.height() != camera_.height))
    throw Error((frame.color_file.empty() ? "frame " + std::to_string(frame.index) : frame.color_file) +
                ": colour size differs from the camera's");
  ++frames_;
  FrameResult r;
  r.index = frame.index;
  r.timestamp_s = frame.timestamp_s;

  auto integrate_at = [&](const SE3& T) {
    const auto t0 = std::chrono::steady_clock::now();
    fusion::integrate(grid_, frame.depth, frame.color, camera_, T, config_.integrate, &store_);
    if (config_.stream_radius_m > 0) fusion::stream_out(grid_, store_, T.translation(), config_.stream_radius_m);
    r.ms.integrate = ms_since(t0);
    r.integrated = true;
  };
  auto lose = [&](std::string why) {
    ++lost_;
    was_lost_ = true;
    r.state = TrackState::lost;
    r.pose_valid = false;
    r.T_world_camera = last_good_.value_or(SE3());
    r.message = std::move(why);
    return r;
  };

  if (!registration_) {  // groundtruth: fusion only
    if (!frame.T_world_camera_gt) return lose("no ground-truth pose for this frame");
    r.state = TrackState::groundtruth;
    r.T_world_camera = *frame.T_world_camera_gt;
    r.pose_valid = true;
    integrate_at(r.T_world_camera);
    last_good_ = r.T_world_camera;
    last_good_time_s_ = frame.timestamp_s;
    return r;
  }

  FramePyramid current;
  {
    const auto t0 = std::chrono::steady_clock::now();
    FramePyramidOptions po = config_.pyramid;
    po.first_level = config_.tracking_level;
    current = build_frame_pyramid(frame.depth, has_color ? &frame.color : nullptr, camera_, po);
    r.ms.preprocess = ms_since(t0);
  }

  // Accepting a pose: integrate, raycast the model there, and make this frame the photometric reference.
  auto accept = [&](const SE3& T_world_cur, TrackState state) {
    r.state = state;
    r.T_world_camera = T_world_cur;
    r.pose_valid = true;
    const bool poor = r.registration && r.registration->status == RegistrationStatus::poor;
    if (!poor || config_.integrate_poor) integrate_at(T_world_cur);
    const auto t0 = std::chrono::steady_clock::now();
    // The frame just integrated from this pose tells each ray where the surface is (fusion/raycast.h depth_hint):
    // its depth at the tracking resolution, from the pyramid's vertices. Where the frame has no depth, the last
    // model raycast moved to this pose (fusion::forward_project_depth) does: those rays would otherwise march
    // their tile's whole depth range.
    fusion::RaycastOptions ro = config_.raycast;
    DepthImage hint;
    if (r.integrated && !current.levels.empty()) {
      const VertexMap& v = current.levels[0].vertices;
      if (reference_->valid && config_.model_hint)
        fusion::forward_project_depth(reference_->model.vertices, T_world_cur.inverse() * reference_->T_world_model,
                                      tracking_camera_, &hint);
      else
        hint = DepthImage(v.width(), v.height(), 0.0f);
      for (int y = 0; y < v.height(); ++y)
        for (int x = 0; x < v.width(); ++x)
          if (v(x, y).w != 0.0f) hint(x, y) = v(x, y).z;
      ro.depth_hint = &hint;
    }
    fusion::raycast(grid_, tracking_camera_, T_world_cur, ro, &reference_->model);
    reference_->T_world_model = T_world_cur;
    reference_->pyramid = build_model_pyramid(reference_->model.vertices, reference_->model.normals, nullptr,
                                              tracking_camera_, config_.pyramid.levels);
    // The frame's intensity levels become the photometric reference; nothing else of it is needed again.
    for (int l = 0; l < reference_->pyramid.num_levels() && l < current.num_levels(); ++l) {
      FramePyramidLevel& dst = reference_->pyramid.levels[size_t(l)];
      FramePyramidLevel& src = current.levels[size_t(l)];
      dst.intensity = std::move(src.intensity);
      dst.grad_x = std::move(src.grad_x);
      dst.grad_y = std::move(src.grad_y);
    }
    reference_->valid = reference_->model.hit_count > 0;
    r.ms.raycast = ms_since(t0);
    last_good_ = T_world_cur;
    last_good_time_s_ = frame.timestamp_s;
    was_lost_ = false;
    return r;
  };

  if (!last_good_ || !reference_->valid) {
    // Initialisation: place the first frame, integrate it. A frame that leaves the map without a surface to track
    // against (no valid depth) does not count: the next frame initialises again.
    // Mid-sequence (the map's surface went out of view) the pose stays where tracking left it: ground truth is only
    // ever used to place the very first frame.
    const SE3 T0 = last_good_ ? *last_good_ : frame.T_world_camera_gt.value_or(SE3());
    const std::optional<SE3> before = last_good_;
    accept(T0, TrackState::initialised);
    if (!reference_->valid) {
      last_good_ = before;
      was_lost_ = true;
      ++lost_;
      r.state = TrackState::lost;
      r.pose_valid = false;
      r.message = "no surface seen yet: the map cannot be initialised from this frame";
    }
    return r;
  }

  const bool prior = config_.constant_velocity && !was_lost_;
  const SE3 guess = prior ? velocity_ : SE3();
  {
    const auto t0 = std::chrono::steady_clock::now();
    r.registration = registration_->align(current, reference_->pyramid, guess);
    r.ms.track = ms_since(t0);
  }
  const RegistrationResult& reg = *r.registration;
  if (!reg.usable()) return lose(std::string("registration ") + hf::to_string(reg.status) + ": " + reg.message);
  if (reg.degenerate_dims > config_.max_degenerate_dims)
    return lose("registration degenerate in " + std::to_string(reg.degenerate_dims) + " directions (at most " +
                std::to_string(config_.max_degenerate_dims) + " accepted)");
  // Plausibility against the sensor clock; a frame rate of 30 Hz when stamps are missing or out of order.
  double dt = frame.timestamp_s - last_good_time_s_;
  if (!(dt > 1e-6)) dt = 1.0 / 30.0;
  const double speed = reg.T_ref_cur.translation().norm() / dt;
  const double angular = reg.T_ref_cur.log().head<3>().norm() * 180.0 / M_PI / dt;
  if (speed > config_.max_speed_m_per_s)
    return lose("implausible motion: " + std::to_string(speed) + " m/s > max_speed_m_per_s " +
                std::to_string(config_.max_speed_m_per_s));
  if (angular > config_.max_angular_speed_deg_per_s)
    return lose("implausible rotation: " + std::to_string(angular) + " deg/s > max_angular_speed_deg_per_s " +
                std::to_string(config_.max_angular_speed_deg_per_s));
  {
    const Consistency cons = depth_consistency(current.levels[0].vertices, reference_->model, tracking_camera_, reg.T_ref_cur,
                                               config_.volume.voxel_m);
    if (cons.sampled > 0 && double(cons.overlap) >= config_.min_overlap * double(cons.sampled) &&
        double(cons.consistent) < config_.min_consistent * double(cons.overlap))
      return lose("depth disagrees with the map: " + std::to_string(cons.consistent) + " of " +
                  std::to_string(cons.overlap) + " overlapping samples consistent (min_consistent " +
                  std::to_string(config_.min_consistent) + ")");
  }
  const bool recovering = was_lost_;
  // After a loss the motion spans several frames: no prior for the next one rather than a wrong one.
  velocity_ = recovering ? SE3() : reg.T_ref_cur;
  return accept(*last_good_ * reg.T_ref_cur, recovering ? TrackState::recovered : TrackState::tracked);
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

}  // namespace hf::slam
