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

// --- The configuration as one list of named fields, visited both ways (to JSON and from JSON) ---------------------

const char* robust_name(RobustKernel k) {
  switch (k) {
    case RobustKernel::none: return "none";
    case RobustKernel::huber: return "huber";
    case RobustKernel::student_t: return "student_t";
  }
  return "none";
}

struct ToJson {
  nlohmann::json* j;
  template <class T>
  void operator()(const char* key, T& value) {
    if constexpr (std::is_same_v<T, RobustKernel>) {
      (*j)[key] = robust_name(value);
    } else {
      (*j)[key] = value;
    }
  }
};

struct FromJson {
  const nlohmann::json* j;
  std::string where;  // "config.json: registration_options"
  size_t used = 0;
  template <class T>
  void operator()(const char* key, T& value) {
    auto it = j->find(key);
    if (it == j->end()) return;
    ++used;
    const std::string name = where + "." + key;
    if constexpr (std::is_same_v<T, RobustKernel>) {
      if (!it->is_string()) throw Error(name + ": expected a string (none, huber, student_t)");
      const std::string s = it->get<std::string>();
      if (s == "none") value = RobustKernel::none;
      else if (s == "huber") value = RobustKernel::huber;
      else if (s == "student_t") value = RobustKernel::student_t;
      else throw Error(name + ": unknown robust kernel '" + s + "' (none, huber, student_t)");
    } else if constexpr (std::is_same_v<T, bool>) {
      if (!it->is_boolean()) throw Error(name + ": expected true or false");
      value = it->get<bool>();
    } else if constexpr (std::is_same_v<T, std::string>) {
      if (!it->is_string()) throw Error(name + ": expected a string");
      value = it->get<std::string>();
    } else if constexpr (std::is_same_v<T, std::vector<int>>) {
      if (!it->is_array()) throw Error(name + ": expected an array of integers");
      std::vector<int> v;
      for (const auto& e : *it) {
        if (!e.is_number_integer() || e.get<long long>() < -1000000 || e.get<long long>() > 1000000 ||
            (e.is_number_unsigned() && e.get<unsigned long long>() > 1000000))
          throw Error(name + ": expected an array of integers");
        v.push_back(int(e.get<long long>()));
      }
      value = v;
    } else if constexpr (std::is_integral_v<T>) {
      // Range-checked in the widest types, so no narrowing conversion ever runs on an out-of-range value.
      bool ok = it->is_number_integer();
      if (ok && it->is_number_unsigned()) {
        ok = it->get<unsigned long long>() <= static_cast<unsigned long long>(std::numeric_limits<T>::max());
      } else if (ok) {
        const long long v = it->get<long long>();
        ok = v >= static_cast<long long>(std::numeric_limits<T>::min()) &&
             (v < 0 || static_cast<unsigned long long>(v) <= static_cast<unsigned long long>(std::numeric_limits<T>::max()));
      }
      if (!ok) throw Error(name + ": expected an integer in [" + std::to_string(std::numeric_limits<T>::min()) + ", " +
                           std::to_string(std::numeric_limits<T>::max()) + "]");
      value = it->get<T>();
    } else {
      if (!it->is_number()) throw Error(name + ": expected a number");
      const double v = it->get<double>();
      if (!std::isfinite(v) || std::abs(v) > double(std::numeric_limits<T>::max()))
        throw Error(name + ": number out of range");
      value = static_cast<T>(v);
    }
  }
};

template <class V>
void visit(V&& v, fusion::VolumeParams& p) {
  v("voxel_m", p.voxel_m);
  v("truncation_vox", p.truncation_vox);
  v("max_weight", p.max_weight);
  v("capacity_blocks", p.capacity_blocks);
}
template <class V>
void visit(V&& v, fusion::IntegrateParams& p) {
  v("min_depth_m", p.min_depth_m);
  v("max_depth_m", p.max_depth_m);
  v("observation_weight", p.observation_weight);
  v("point_to_plane", p.point_to_plane);
}
template <class V>
void visit(V&& v, fusion::RaycastOptions& p) {
  v("min_depth_m", p.min_depth_m);
  v("max_depth_m", p.max_depth_m);
  v("step_fraction", p.step_fraction);
  v("min_step_vox", p.min_step_vox);
  v("min_weight", p.min_weight);
  v("refine_tol_vox", p.refine_tol_vox);
}
template <class V>
void visit(V&& v, FramePyramidOptions& p) {
  v("levels", p.levels);
  v("bilateral_filter", p.bilateral_filter);
  v("max_depth_m", p.max_depth_m);
  v("min_depth_m", p.min_depth_m);
}
template <class V>
void visit(V&& v, RegistrationOptions& o) {
  v("iterations", o.iterations);
  v("min_step_rotation_rad", o.min_step_rotation_rad);
  v("min_step_translation_m", o.min_step_translation_m);
  v("max_dist_m", o.max_dist_m);
  v("max_normal_angle_deg", o.max_normal_angle_deg);
  v("robust_icp", o.robust_icp);
  v("huber_icp_m", o.huber_icp_m);
  v("robust_rgb", o.robust_rgb);
  v("huber_rgb", o.huber_rgb);
  v("t_dof", o.t_dof);
  v("t_sigma_rgb_init", o.t_sigma_rgb_init);
  v("t_sigma_rgb_min", o.t_sigma_rgb_min);
  v("t_sigma_icp_m", o.t_sigma_icp_m);
  v("rgb_weight", o.rgb_weight);
  v("min_gradient", o.min_gradient);
  v("photometric_occlusion_check", o.photometric_occlusion_check);
  v("degeneracy_threshold", o.degeneracy_threshold);
  v("min_inliers", o.min_inliers);
  v("poor_inlier_ratio", o.poor_inlier_ratio);
  v("max_translation_m", o.max_translation_m);
  v("max_rotation_deg", o.max_rotation_deg);
  v("max_final_step_translation_m", o.max_final_step_translation_m);
  v("max_final_step_rotation_rad", o.max_final_step_rotation_rad);
}
template <class V>
void visit_scalars(V&& v, PipelineConfig& c) {
  v("registration", c.registration);
  v("backend", c.backend);
  v("tracking_level", c.tracking_level);
  v("rgb_weight", c.rgb_weight);
  v("constant_velocity", c.constant_velocity);
  v("max_speed_m_per_s", c.max_speed_m_per_s);
  v("max_angular_speed_deg_per_s", c.max_angular_speed_deg_per_s);
  v("max_degenerate_dims", c.max_degenerate_dims);
  v("integrate_poor", c.integrate_poor);
  v("model_hint", c.model_hint);
  v("min_overlap", c.min_overlap);
  v("min_consistent", c.min_consistent);
  v("stream_radius_m", c.stream_radius_m);
}

template <class S>
nlohmann::json section_to_json(S& s) {
  nlohmann::json j = nlohmann::json::object();
  visit(ToJson{&j}, s);
  return j;
}

template <class S>
void section_from_json(const nlohmann::json& j, const std::string& where, S& s) {
  if (!j.is_object()) throw Error(where + ": expected an object");
  FromJson f{&j, where};
  visit(f, s);
  // Unknown keys are mistakes (a typo would otherwise silently keep the default).
  nlohmann::json known = section_to_json(s);
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.contains(it.key())) throw Error(where + ": unknown key '" + it.key() + "'");
}

RegistrationOptions effective_registration_options(const PipelineConfig& c) {
  if (c.registration_options) return *c.registration_options;
  RegistrationOptions o = default_registration_options(c.registration);
  o.rgb_weight = c.rgb_weight;
  return o;
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

// --- Configuration ----------------------------------------------------------------------------------------------

void PipelineConfig::validate() const {
  if (registration != "groundtruth") {
    const auto names = registration_names();
    if (std::find(names.begin(), names.end(), registration) == names.end()) {
      std::string known = "groundtruth";
      for (const auto& n : names) known += ", " + n;
      throw Error("unknown registration method '" + registration + "' (known: " + known + ")");
    }
  }
  volume.validate();
  raycast.validate();
  if (!(integrate.min_depth_m >= 0 && integrate.min_depth_m < integrate.max_depth_m &&
        std::isfinite(integrate.max_depth_m)))
    throw Error("integrate: need 0 <= min_depth_m < max_depth_m (finite)");
  if (!(integrate.observation_weight > 0 && std::isfinite(integrate.observation_weight)))
    throw Error("integrate.observation_weight must be positive");
  if (pyramid.levels < 1 || pyramid.levels > 6) throw Error("pyramid.levels must be in [1, 6]");
  if (tracking_level < 0 || tracking_level > 2) throw Error("tracking_level must be 0, 1 or 2");
  if (!(rgb_weight >= 0 && std::isfinite(rgb_weight))) throw Error("rgb_weight must be finite and >= 0");
  if (registration_options) registration_options->validate();
  if (!(max_speed_m_per_s > 0)) throw Error("max_speed_m_per_s must be positive");
  if (!(max_angular_speed_deg_per_s > 0)) throw Error("max_angular_speed_deg_per_s must be positive");
  if (max_degenerate_dims < 0 || max_degenerate_dims > 6) throw Error("max_degenerate_dims must be in [0, 6]");
  if (!(min_overlap >= 0 && min_overlap <= 1)) throw Error("min_overlap must be in [0, 1]");
  if (!(min_consistent >= 0 && min_consistent <= 1)) throw Error("min_consistent must be in [0, 1]");
  if (!(stream_radius_m >= 0) || !std::isfinite(stream_radius_m)) throw Error("stream_radius_m must be >= 0");
}

nlohmann::json config_to_json(const PipelineConfig& config) {
  PipelineConfig c = config;  // the visitors take non-const references
  nlohmann::json j = nlohmann::json::object();
  visit_scalars(ToJson{&j}, c);
  j["volume"] = section_to_json(c.volume);
  j["integrate"] = section_to_json(c.integrate);
  j["raycast"] = section_to_json(c.raycast);
  j["pyramid"] = section_to_json(c.pyramid);
  // Always write the options in force, so a report says exactly what ran.
  RegistrationOptions r = c.registration == "groundtruth" ? RegistrationOptions{} : effective_registration_options(c);
  j["registration_options"] = section_to_json(r);
  return j;
}

PipelineConfig config_from_json(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw Error(where + ": expected a JSON object");
  PipelineConfig c;
  FromJson f{&j, where};
  visit_scalars(f, c);
  // The method first: the registration options start from its defaults.
  static const char* sections[] = {"volume", "integrate", "raycast", "pyramid", "registration_options"};
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    if (std::find(std::begin(sections), std::end(sections), k) != std::end(sections)) continue;
    nlohmann::json probe;
    visit_scalars(ToJson{&probe}, c);
    if (!probe.contains(k)) throw Error(where + ": unknown key '" + k + "'");
  }
  if (j.contains("volume")) section_from_json(j["volume"], where + ": volume", c.volume);
  if (j.contains("integrate")) section_from_json(j["integrate"], where + ": integrate", c.integrate);
  if (j.contains("raycast")) section_from_json(j["raycast"], where + ": raycast", c.raycast);
  if (j.contains("pyramid")) section_from_json(j["pyramid"], where + ": pyramid", c.pyramid);
  if (j.contains("registration_options") && !j["registration_options"].is_null()) {
    RegistrationOptions r =
        c.registration == "groundtruth" ? RegistrationOptions{} : effective_registration_options(c);
    section_from_json(j["registration_options"], where + ": registration_options", r);
    c.registration_options = r;
  }
  try {
    c.validate();
  } catch (const Error& e) {
    throw Error(where + ": " + e.what());
  }
  return c;
}

PipelineConfig load_config(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw Error(path + ": cannot open config file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_config(ss.str(), path);
}

PipelineConfig parse_config(const std::string& text, const std::string& path) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // Turn the byte offset into a line number, as every other parser of ours reports.
    size_t line = 1;
    for (size_t i = 0; i < e.byte && i < text.size(); ++i) line += text[i] == '\n';
    throw ParseError(path, line, "invalid JSON");
  } catch (const nlohmann::json::exception& e) {
    throw Error(path + ": invalid JSON (" + e.what() + ")");  // e.g. a number out of double range
  }
  return config_from_json(j, path);
}

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
