#include "slam/pipeline_config.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "core/bounded_read.h"
#include "core/error.h"
#include "core/number_text.h"
#include "registration/reduction.h"
#include "registration/so3_prealign.h"
#include "slam/config_reference.h"
#include "slam/appearance.h"

namespace hf::slam {
namespace {

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
    } else if constexpr (std::is_same_v<T, float>) {
      (*j)[key] = float_as_shortest_double(value);  // 0.1, not 0.10000000149011612
    } else {
      (*j)[key] = value;
    }
  }
};

struct FromJson {
  const nlohmann::json* j;
  std::string where;  // "config.json: registration_options"
  size_t used = 0;
  // "" (top level) or the section ("volume"): numbers are checked against the row "section.key" of the reference
  // (slam/config_reference.h). registration_options' ranges are each method's validate()'s to enforce.
  std::string section;

  // The reference's range for `key`, where it has a row.
  void check_range(const char* key, double v, const std::string& name) const {
    if (section == "registration_options") return;
    const ConfigKey* row = find_config_key(section.empty() ? std::string(key) : section + "." + key);
    if (row && !in_config_range(*row, v))
      throw Error(name + ": expected " + describe_range(*row) + ", got " + number_for_message(v));
  }
  template <class T>
  void operator()(const char* key, T& value) {
    auto it = j->find(key);
    if (it == j->end()) return;
    ++used;
    // "x.json: constant_velocity" at the top level, "x.json: volume.voxel_m" in a section.
    const std::string name = where + (where.find(": ") == std::string::npos ? ": " : ".") + key;
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
      // The field's own range is validate()'s to state (e.g. capacity_blocks in [1, 2^26]); this only keeps the
      // conversion defined, so a 64-bit field says nothing about its type's range.
      if (!ok && sizeof(T) >= 8) throw Error(name + ": expected an integer, got one out of range");
      if (!ok) throw Error(name + ": expected an integer in [" + std::to_string(std::numeric_limits<T>::min()) + ", " +
                           std::to_string(std::numeric_limits<T>::max()) + "]");
      value = it->get<T>();
      check_range(key, double(value), name);
    } else {
      if (!it->is_number()) throw Error(name + ": expected a number");
      const double v = it->get<double>();
      if (!std::isfinite(v) || std::abs(v) > double(std::numeric_limits<T>::max()))
        throw Error(name + ": number out of range");
      check_range(key, v, name);
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
  v("truncation_depth_ref_m", p.truncation_depth_ref_m);
  v("truncation_min_fraction", p.truncation_min_fraction);
  v("weight_depth_ref_m", p.weight_depth_ref_m);
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
  v("fill_holes_levels", p.fill_holes_levels);
}
// The driver's and the method's own knobs, by the keys registration declares (registration.h OptionVisitor).
template <class V>
void visit(V&& v, RegistrationOptions& o) {
  OptionVisitorFor<std::remove_reference_t<V>> adaptor(v);
  o.visit(adaptor);
}
template <class V>
void visit(V&& v, KeyframeOptions& o) {
  v("min_translation_m", o.min_translation_m);
  v("min_rotation_deg", o.min_rotation_deg);
  v("max_frames_between", o.max_frames_between);
  v("memory_budget_mb", o.memory_budget_mb);
  v("jpeg_quality", o.jpeg_quality);
}
template <class V>
void visit(V&& v, RelocalisationOptions& o) {
  v("enabled", o.enabled);
  v("candidates", o.candidates);
  v("appearance", o.appearance);
}
template <class V>
void visit(V&& v, LoopClosureOptions& o) {
  v("enabled", o.enabled);
  v("candidates", o.candidates);
  v("min_keyframe_gap", o.min_keyframe_gap);
  v("min_path_m", o.min_path_m);
  v("max_distance_m", o.max_distance_m);
  v("max_angle_deg", o.max_angle_deg);
  v("min_inlier_ratio", o.min_inlier_ratio);
  v("min_consistent", o.min_consistent);
  v("loop_loss_chi2", o.graph.loop_loss_chi2);
  v("loop_reject_chi2", o.graph.loop_reject_chi2);
  v("max_iterations", o.graph.max_iterations);
  v("time_budget_ms", o.graph.time_budget_ms);
  v("background", o.background);
  v("apply_delay_frames", o.apply_delay_frames);
  v("window_keyframes", o.window_keyframes);
  v("window_information_scale", o.window_information_scale);
  v("window_tracking_information_scale", o.window_tracking_information_scale);
}
template <class V>
void visit(V&& v, ReintegrationOptions& o) {
  v("enabled", o.enabled);
  v("min_translation_m", o.min_translation_m);
  v("min_rotation_deg", o.min_rotation_deg);
  v("frames_per_step", o.frames_per_step);
  v("frames_after_loop", o.frames_after_loop);
  v("frames_after_loop_per_step", o.frames_after_loop_per_step);
  v("budget_ms_per_frame", o.budget_ms_per_frame);
  v("min_displacement_vox", o.min_displacement_vox);
  v("memory_budget_mb", o.memory_budget_mb);
}
template <class V>
void visit(V&& v, ColourCheckOptions& o) {
  v("enabled", o.enabled);
  v("window_estimates", o.window_estimates);
  v("frame_step", o.frame_step);
  v("max_scale_error", o.max_scale_error);
  v("max_zoom", o.max_zoom);
  v("max_shift_fraction", o.max_shift_fraction);
  v("min_edge_fraction", o.min_edge_fraction);
  v("max_chamfer_px", o.max_chamfer_px);
  v("depth_only_registration", o.depth_only_registration);
}
template <class V>
void visit_scalars(V&& v, PipelineConfig& c) {
  v("registration", c.registration);
  v("fallback_registration", c.fallback_registration);
  v("seed_registration", c.seed_registration);
  v("seed_min_motion_m", c.seed_min_motion_m);
  v("seed_min_motion_deg", c.seed_min_motion_deg);
  v("seed_on_failure", c.seed_on_failure);
  v("backend", c.backend);
  v("tracking_level", c.tracking_level);
  v("constant_velocity", c.constant_velocity);
  v("velocity_by_time", c.velocity_by_time);
  v("wide_basin_without_prior", c.wide_basin_without_prior);
  v("max_speed_m_per_s", c.max_speed_m_per_s);
  v("max_angular_speed_deg_per_s", c.max_angular_speed_deg_per_s);
  v("max_degenerate_dims", c.max_degenerate_dims);
  v("integrate_poor", c.integrate_poor);
  v("model_hint", c.model_hint);
  v("tracking_raycast", c.tracking_raycast);
  v("tracking_raycast_dilate_px", c.tracking_raycast_dilate_px);
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
  FromJson f{&j, where, 0, ""};
  // "x.json: volume" -> "volume": the section's rows in the reference.
  const size_t colon = where.rfind(": ");
  f.section = colon == std::string::npos ? where : where.substr(colon + 2);
  visit(f, s);
  // Unknown keys are mistakes (a typo would otherwise silently keep the default).
  nlohmann::json known = section_to_json(s);
  for (auto it = j.begin(); it != j.end(); ++it)
    if (!known.contains(it.key())) throw Error(where + ": unknown key '" + it.key() + "'");
}

// registration_options as written before methods owned their knobs (report.json up to cc8db77 holds every
// method's keys in one object): former keys are renamed or dropped by registration's rule (registration.h,
// migrate_registration_key); the method's own keys and keys that were never options pass unchanged (the latter are
// then rejected as unknown).
nlohmann::json migrate_registration_options(const nlohmann::json& j, const RegistrationOptions& now) {
  if (!j.is_object()) return j;
  RegistrationOptions copy = now;
  const nlohmann::json known = section_to_json(copy);
  nlohmann::json out = nlohmann::json::object();
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::optional<std::string> key =
        known.contains(it.key()) ? std::optional<std::string>(it.key()) : migrate_registration_key(now, it.key());
    if (!key) {
      out[it.key()] = it.value();
    } else if (!key->empty() && !(*key != it.key() && j.contains(*key))) {
      out[*key] = it.value();
    }
  }
  return out;
}

}  // namespace

RegistrationOptions pipeline_registration_options(const std::string& method, int levels) {
  RegistrationOptions o = default_registration_options(method);
  o.set("rgb_weight", kPipelineRgbWeight);  // methods without photometric rows have no such knob
  // A registry default's wide basin for guess-free pairs (combined: rotation-first, 5 levels) is not the
  // pipeline's: it tracks from a motion prior, where they cost time and no accuracy (bench/results/accuracy/
  // large_motion.md), at the depth of the configured pyramid (not the default one: a 4-level pyramid tracks on 4
  // levels where the method's defaults have them).
  o.driver.so3_iterations.clear();
  const size_t n = size_t(std::max(1, levels));
  if (o.driver.iterations.size() > n) o.driver.iterations.resize(n);
  return o;
}

RegistrationOptions pipeline_wide_basin_options(RegistrationOptions o) {
  std::vector<int>& it = o.driver.iterations;
  it.push_back(it.empty() ? 4 : std::max(4, it.back()));
  // so3_prealign reads intensity: a depth-only method skips it (gauss_newton.cpp), so setting it is harmless.
  o.driver.so3_iterations = wide_basin_so3_iterations();
  return o;
}

RegistrationOptions registration_options_from_json(const std::string& method, const nlohmann::json& j,
                                                   const std::string& where) {
  RegistrationOptions r = default_registration_options(method);
  section_from_json(j, where, r);  // keys typed now: no migration of former spellings
  r.validate();
  return r;
}

RegistrationOptions effective_registration_options(const PipelineConfig& c) {
  if (c.registration_options) return *c.registration_options;
  return pipeline_registration_options(c.registration, c.pyramid.levels);
}


// --- Configuration ----------------------------------------------------------------------------------------------

void PipelineConfig::validate() const {
  // Before any input is opened (make_backend would refuse it only when the pipeline is built).
  if (const auto names = backend_names(); std::find(names.begin(), names.end(), backend) == names.end())
    throw Error("unknown reduction backend '" + backend + "' (known: cpu, opencl)");
  if (registration != "groundtruth") {
    const auto names = registration_names();
    if (std::find(names.begin(), names.end(), registration) == names.end()) {
      std::string known = "groundtruth";
      for (const auto& n : names) known += ", " + n;
      throw Error("unknown registration method '" + registration + "' (known: " + known + ")");
    }
  }
  // The optional methods beside the primary: empty = none, else a registry name.
  for (const auto& [key, method] : {std::pair<const char*, const std::string*>{"fallback_registration",
                                                                               &fallback_registration},
                                    {"seed_registration", &seed_registration},
                                    {"seed_on_failure", &seed_on_failure}}) {
    const auto names = registration_names();
    if (!method->empty() && std::find(names.begin(), names.end(), *method) == names.end())
      throw Error(std::string("unknown ") + key + " '" + *method + "'");
  }
  if (!(seed_min_motion_m >= 0.0) || !(seed_min_motion_deg >= 0.0) || !std::isfinite(seed_min_motion_m) ||
      !std::isfinite(seed_min_motion_deg))
    throw Error("seed_min_motion_m and seed_min_motion_deg must be finite and >= 0");
  keyframes.validate();
  loop_closure.validate();
  reintegration.validate();
  colour_check.validate();
  if (colour_check.enabled) {
    const auto names = registration_names();
    if (std::find(names.begin(), names.end(), colour_check.depth_only_registration) == names.end())
      throw Error("unknown colour_check.depth_only_registration '" + colour_check.depth_only_registration + "'");
  }
  if (loop_closure.graph.threads < 1 || loop_closure.graph.threads > 64)
    throw Error("loop_closure: threads must be in [1, 64]");
  if (relocalisation.candidates < 1 || relocalisation.candidates > 100)
    throw Error("relocalisation.candidates must be in [1, 100]");
  if (!relocalisation.appearance.empty()) {
    const auto names = appearance_index_names();
    if (std::find(names.begin(), names.end(), relocalisation.appearance) == names.end())
      throw Error("unknown relocalisation.appearance '" + relocalisation.appearance + "'");
  }
  volume.validate();
  raycast.validate();
  if (!(integrate.min_depth_m >= 0 && integrate.min_depth_m < integrate.max_depth_m &&
        std::isfinite(integrate.max_depth_m)))
    throw Error("integrate: need 0 <= min_depth_m < max_depth_m (finite)");
  if (!(integrate.observation_weight > 0 && std::isfinite(integrate.observation_weight)))
    throw Error("integrate.observation_weight must be positive");
  if (!(integrate.truncation_depth_ref_m >= 0.0f && std::isfinite(integrate.truncation_depth_ref_m)))
    throw Error("integrate.truncation_depth_ref_m must be finite and >= 0");
  if (!(integrate.truncation_min_fraction > 0.0f && integrate.truncation_min_fraction <= 1.0f))
    throw Error("integrate.truncation_min_fraction must be in (0, 1]");
  if (!(integrate.weight_depth_ref_m >= 0.0f && std::isfinite(integrate.weight_depth_ref_m)))
    throw Error("integrate.weight_depth_ref_m must be finite and >= 0");
  if (pyramid.levels < 1 || pyramid.levels > 6) throw Error("pyramid.levels must be in [1, 6]");
  if (pyramid.fill_holes_levels < 0 || pyramid.fill_holes_levels > 8)
    throw Error("pyramid.fill_holes_levels must be in [0, 8]");
  if (tracking_level < 0 || tracking_level > 2) throw Error("tracking_level must be 0, 1 or 2");
  if (tracking_raycast != "full" && tracking_raycast != "sampled")
    throw Error("tracking_raycast must be \"full\" or \"sampled\", got \"" + tracking_raycast + "\"");
  if (tracking_raycast_dilate_px < 0 || tracking_raycast_dilate_px > 16)
    throw Error("tracking_raycast_dilate_px must be in [0, 16]");
  if (registration_options) registration_options->validate();
  if (depth_only_registration_options) depth_only_registration_options->validate();
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
  j["keyframes"] = section_to_json(c.keyframes);
  j["relocalisation"] = section_to_json(c.relocalisation);
  j["loop_closure"] = section_to_json(c.loop_closure);
  j["reintegration"] = section_to_json(c.reintegration);
  j["colour_check"] = section_to_json(c.colour_check);
  // Always write the options in force, so a report says exactly what ran.
  RegistrationOptions r = c.registration == "groundtruth" ? RegistrationOptions{} : effective_registration_options(c);
  j["registration_options"] = section_to_json(r);
  if (c.depth_only_registration_options) {
    RegistrationOptions d = *c.depth_only_registration_options;
    j["depth_only_registration_options"] = section_to_json(d);
  }
  return j;
}

namespace {

// config_from_json without the file name on every error; the wrapper below adds it where missing.
PipelineConfig pipeline_config_from_json_unnamed(const nlohmann::json& j, const std::string& where) {
  if (!j.is_object()) throw Error(where + ": expected a JSON object");
  PipelineConfig c;
  FromJson f{&j, where, 0, ""};
  visit_scalars(f, c);
  // The method first: the registration options start from its defaults.
  static const char* sections[] = {"volume", "integrate", "raycast", "pyramid", "registration_options",
                                   "keyframes", "relocalisation", "loop_closure", "reintegration",
                                   "colour_check", "depth_only_registration_options"};
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string& k = it.key();
    if (std::find(std::begin(sections), std::end(sections), k) != std::end(sections)) continue;
    if (k == "rgb_weight") continue;  // a former top-level key, read into registration_options below
    nlohmann::json probe;
    visit_scalars(ToJson{&probe}, c);
    if (!probe.contains(k)) throw Error(where + ": unknown key '" + k + "'");
  }
  if (j.contains("volume")) section_from_json(j["volume"], where + ": volume", c.volume);
  if (j.contains("integrate")) section_from_json(j["integrate"], where + ": integrate", c.integrate);
  if (j.contains("raycast")) section_from_json(j["raycast"], where + ": raycast", c.raycast);
  if (j.contains("pyramid")) section_from_json(j["pyramid"], where + ": pyramid", c.pyramid);
  if (j.contains("keyframes")) section_from_json(j["keyframes"], where + ": keyframes", c.keyframes);
  if (j.contains("relocalisation"))
    section_from_json(j["relocalisation"], where + ": relocalisation", c.relocalisation);
  if (j.contains("loop_closure")) section_from_json(j["loop_closure"], where + ": loop_closure", c.loop_closure);
  if (j.contains("reintegration"))
    section_from_json(j["reintegration"], where + ": reintegration", c.reintegration);
  if (j.contains("colour_check")) section_from_json(j["colour_check"], where + ": colour_check", c.colour_check);
  if (j.contains("depth_only_registration_options") && !j["depth_only_registration_options"].is_null()) {
    RegistrationOptions r = pipeline_registration_options(c.colour_check.depth_only_registration, c.pyramid.levels);
    section_from_json(j["depth_only_registration_options"], where + ": depth_only_registration_options", r);
    c.depth_only_registration_options = r;
  }
  if (j.contains("registration_options") && !j["registration_options"].is_null()) {
    RegistrationOptions r =
        c.registration == "groundtruth" ? RegistrationOptions{} : effective_registration_options(c);
    section_from_json(migrate_registration_options(j["registration_options"], r), where + ": registration_options",
                      r);
    c.registration_options = r;
  }
  // Configs written before registration options had one home kept lambda at the top level (as "rgb_weight"); it
  // applies where registration_options does not set it itself.
  if (j.contains("rgb_weight") && c.registration != "groundtruth") {
    const nlohmann::json& w = j["rgb_weight"];
    if (!w.is_number() || !std::isfinite(w.get<double>()) || w.get<double>() < 0)
      throw Error(where + ".rgb_weight: expected a finite number >= 0");
    const bool section_sets_it = j.contains("registration_options") && j["registration_options"].is_object() &&
                                 j["registration_options"].contains("rgb_weight");
    if (!section_sets_it) {
      RegistrationOptions r = effective_registration_options(c);
      r.set("rgb_weight", w.get<double>());
      c.registration_options = r;
    }
  }
  c.validate();
  return c;
}

}  // namespace

PipelineConfig config_from_json(const nlohmann::json& j, const std::string& where) {
  // Every error names the file: the method's defaults are looked up (and an unknown method refused) before
  // validate() runs, by code that does not know where the configuration came from.
  try {
    return pipeline_config_from_json_unnamed(j, where);
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    const std::string message = e.what();
    if (message.rfind(where + ":", 0) == 0 || message.rfind(where + ".", 0) == 0) throw;
    throw Error(where + ": " + message);
  }
}

PipelineConfig load_config(const std::string& path) {
  // Regular files only, bounded: a FIFO or /dev/zero given as --config is refused at once (core/bounded_read.h).
  return parse_config(read_regular_file(path, "config file"), path);
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
  // A whole report.json (its "config" object repeats the run): no configuration has a key "config".
  if (j.is_object() && j.contains("config") && j["config"].is_object())
    return config_from_json(j["config"], path + ": config");
  return config_from_json(j, path);
}

}  // namespace hf::slam
