#include "registration/registration.h"

#include <algorithm>
#include <cmath>
#include <mutex>

#include "core/error.h"

namespace hf {

// The built-in methods' entries (registration/methods.def).
#define HF_REGISTRATION_METHOD(m) RegistrationMethod m##_registration_method();
#include "registration/methods.def"
#undef HF_REGISTRATION_METHOD

namespace {

void check(bool ok, const char* what) { require_option(ok, what); }

struct Registry {
  std::mutex mutex;
  std::vector<RegistrationMethod> methods;  // sorted by name

  Registry() {
#define HF_REGISTRATION_METHOD(m) add(m##_registration_method());
#include "registration/methods.def"
#undef HF_REGISTRATION_METHOD
  }

  void add(const RegistrationMethod& m) {
    if (m.name.empty() || m.defaults == nullptr || m.make == nullptr) {
      throw Error("register_registration: incomplete entry '" + m.name + "'");
    }
    auto at = std::lower_bound(methods.begin(), methods.end(), m.name,
                               [](const RegistrationMethod& e, const std::string& n) { return e.name < n; });
    if (at != methods.end() && at->name == m.name) {
      throw Error("register_registration: '" + m.name + "' is already registered");
    }
    methods.insert(at, m);
  }

  RegistrationMethod find(const std::string& name) {
    const std::lock_guard<std::mutex> lock(mutex);
    for (const RegistrationMethod& e : methods) {
      if (e.name == name) return e;
    }
    std::string known;
    for (const RegistrationMethod& e : methods) known += (known.empty() ? "" : ", ") + e.name;
    throw Error("unknown registration method '" + name + "' (known: " + known + ")");
  }
};

Registry& registry() {
  static Registry r;
  return r;
}

// Sets the numeric field `key` to `value`.
struct KeySetter {
  const std::string& key;
  double value;
  bool found = false;
  template <class T>
  void operator()(const char* k, T& field) {
    if constexpr (std::is_arithmetic_v<T>) {
      if (key == k) {
        field = static_cast<T>(value);
        found = true;
      }
    }
  }
};

}  // namespace

void require_option(bool ok, const char* what) {
  if (!ok) throw Error(std::string("registration options: ") + what);
}

void GaussNewtonOptions::visit(OptionVisitor& v) {
  v("iterations", iterations);
  v("min_step_rotation_rad", min_step_rotation_rad);
  v("min_step_translation_m", min_step_translation_m);
  v("degeneracy_threshold", degeneracy_threshold);
  v("min_inliers", min_inliers);
  v("poor_inlier_ratio", poor_inlier_ratio);
  v("max_translation_m", max_translation_m);
  v("max_rotation_deg", max_rotation_deg);
  v("verify_motion_m", verify_motion_m);
  v("verify_motion_deg", verify_motion_deg);
  v("verify_agreement_m", verify_agreement_m);
  v("verify_agreement_deg", verify_agreement_deg);
  v("max_final_step_translation_m", max_final_step_translation_m);
  v("max_final_step_rotation_rad", max_final_step_rotation_rad);
  int mode = int(row_selection.mode);  // the visitor knows ints, not the enum
  v("row_selection", mode);
  row_selection.mode = PixelSelectionMode(mode);
  v("row_selection_tile_px", row_selection.tile_px);
  v("row_selection_budget", row_selection.budget_per_tile);
  v("row_selection_depth_edge_weight", row_selection.depth_edge_weight);
  v("row_selection_levels", row_selection.levels);
  v("so3_iterations", so3_iterations);
}

void GaussNewtonOptions::validate() const {
  check(!iterations.empty() && iterations.size() <= 8, "iterations must list 1..8 levels");
  for (int n : iterations) check(n >= 0 && n <= 1000, "iterations per level must be in 0..1000");
  check(so3_iterations.size() <= 8, "so3_iterations must list at most 8 levels");
  for (int n : so3_iterations) check(n >= 0 && n <= 1000, "so3_iterations per level must be in 0..1000");
  check(std::isfinite(min_step_rotation_rad) && min_step_rotation_rad >= 0.0, "min_step_rotation_rad must be >= 0");
  check(std::isfinite(min_step_translation_m) && min_step_translation_m >= 0.0,
        "min_step_translation_m must be >= 0");
  check(std::isfinite(verify_motion_m) && verify_motion_m >= 0.0, "verify_motion_m must be finite and >= 0");
  check(std::isfinite(verify_motion_deg) && verify_motion_deg >= 0.0, "verify_motion_deg must be finite and >= 0");
  check(finite_positive(verify_agreement_m), "verify_agreement_m must be finite and > 0");
  check(finite_positive(verify_agreement_deg), "verify_agreement_deg must be finite and > 0");
  check(std::isfinite(degeneracy_threshold) && degeneracy_threshold >= 0.0 && degeneracy_threshold < 1.0,
        "degeneracy_threshold must be in [0, 1)");
  check(min_inliers >= 6, "min_inliers must be >= 6 (six unknowns)");
  check(std::isfinite(poor_inlier_ratio) && poor_inlier_ratio >= 0.0 && poor_inlier_ratio <= 1.0,
        "poor_inlier_ratio must be in [0, 1]");
  check(finite_positive(max_translation_m), "max_translation_m must be finite and > 0");
  check(finite_positive(max_rotation_deg), "max_rotation_deg must be finite and > 0");
  check(finite_positive(max_final_step_translation_m), "max_final_step_translation_m must be finite and > 0");
  check(finite_positive(max_final_step_rotation_rad), "max_final_step_rotation_rad must be finite and > 0");
  row_selection.validate();
}

RegistrationOptions::RegistrationOptions(const GaussNewtonOptions& d, std::unique_ptr<MethodOptions> m)
    : driver(d), method_(std::move(m)) {}

RegistrationOptions::RegistrationOptions(const RegistrationOptions& other)
    : driver(other.driver), method_(other.method_ ? other.method_->clone() : nullptr) {}

RegistrationOptions& RegistrationOptions::operator=(const RegistrationOptions& other) {
  if (this != &other) {
    driver = other.driver;
    method_ = other.method_ ? other.method_->clone() : nullptr;
  }
  return *this;
}

void RegistrationOptions::visit(OptionVisitor& v) {
  driver.visit(v);
  if (method_) method_->visit(v);
}

bool RegistrationOptions::set(const std::string& key, double value) {
  KeySetter setter{key, value};
  OptionVisitorFor<KeySetter> v(setter);
  visit(v);
  return setter.found;
}

void RegistrationOptions::validate() const {
  driver.validate();
  if (method_) method_->validate();
}

void RegistrationOptions::throw_wrong_method() {
  throw Error("registration options: these options belong to another method (or to none)");
}

std::optional<std::string> migrate_registration_key(const RegistrationOptions& now, const std::string& key) {
  // Every key of the former single RegistrationOptions (config.registration_options in report.json).
  static const char* const former[] = {
      "iterations", "min_step_rotation_rad", "min_step_translation_m", "max_dist_m", "max_normal_angle_deg",
      "robust_icp", "huber_icp_m", "robust_rgb", "huber_rgb", "t_dof", "t_sigma_rgb_init", "t_sigma_rgb_min",
      "t_sigma_icp_m", "rgb_weight", "min_gradient", "photometric_occlusion_check", "degeneracy_threshold",
      "min_inliers", "poor_inlier_ratio", "max_translation_m", "max_rotation_deg", "max_final_step_translation_m",
      "max_final_step_rotation_rad"};
  if (std::find(std::begin(former), std::end(former), key) == std::end(former)) return std::nullopt;
  RegistrationOptions copy = now;  // visiting takes non-const fields
  std::vector<std::string> keys;
  copy.for_each_option([&keys](const char* k, auto&) { keys.emplace_back(k); });
  auto has = [&](const char* k) { return std::find(keys.begin(), keys.end(), k) != keys.end(); };
  if (has(key.c_str())) return key;
  if (key == "t_dof" && has("t_dof_icp")) return std::string("t_dof_icp");
  if (key == "max_dist_m" && has("occlusion_max_depth_m")) return std::string("occlusion_max_depth_m");
  return std::string();
}

void register_registration(const RegistrationMethod& method) {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  r.add(method);
}

RegistrationOptions default_registration_options(const std::string& name) { return registry().find(name).defaults(); }

std::unique_ptr<Registration> make_registration(const std::string& name, const std::string& backend) {
  const RegistrationMethod m = registry().find(name);
  return m.make(m.defaults(), make_backend(backend));
}

std::unique_ptr<Registration> make_registration(const std::string& name, const RegistrationOptions& options,
                                                std::unique_ptr<ReductionBackend> backend) {
  return registry().find(name).make(options, std::move(backend));
}

std::vector<std::string> registration_names() {
  Registry& r = registry();
  const std::lock_guard<std::mutex> lock(r.mutex);
  std::vector<std::string> names;
  for (const RegistrationMethod& e : r.methods) names.push_back(e.name);
  return names;
}

}  // namespace hf
