#include "registration/registration.h"

#include <cmath>

#include "core/error.h"
#include "registration/combined.h"
#include "registration/icp.h"
#include "registration/photometric.h"

namespace hf {
namespace {

struct Entry {
  const char* name;
  RegistrationOptions (*defaults)();
  std::unique_ptr<Registration> (*make)(const RegistrationOptions&, std::unique_ptr<ReductionBackend>);
};

// One line per method, sorted by name.
const Entry kMethods[] = {
    {"combined", combined_default_options, make_combined_registration},
    {"icp", icp_default_options, make_icp_registration},
    {"photometric", photometric_default_options, make_photometric_registration},
};

const Entry& find(const std::string& name) {
  for (const Entry& e : kMethods) {
    if (name == e.name) return e;
  }
  std::string known;
  for (const Entry& e : kMethods) known += (known.empty() ? "" : ", ") + std::string(e.name);
  throw Error("unknown registration method '" + name + "' (known: " + known + ")");
}

void check(bool ok, const std::string& what) {
  if (!ok) throw Error("registration options: " + what);
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

}  // namespace

void RegistrationOptions::validate() const {
  check(!iterations.empty() && iterations.size() <= 8, "iterations must list 1..8 levels");
  for (int n : iterations) check(n >= 0 && n <= 1000, "iterations per level must be in 0..1000");
  check(std::isfinite(min_step_rotation_rad) && min_step_rotation_rad >= 0.0, "min_step_rotation_rad must be >= 0");
  check(std::isfinite(min_step_translation_m) && min_step_translation_m >= 0.0,
        "min_step_translation_m must be >= 0");
  check(finite_positive(max_dist_m), "max_dist_m must be finite and > 0");
  check(std::isfinite(max_normal_angle_deg) && max_normal_angle_deg > 0.0f && max_normal_angle_deg <= 180.0f,
        "max_normal_angle_deg must be in (0, 180]");
  check(finite_positive(huber_icp_m), "huber_icp_m must be finite and > 0");
  check(finite_positive(huber_rgb), "huber_rgb must be finite and > 0");
  check(finite_positive(t_dof), "t_dof must be finite and > 0");
  check(finite_positive(t_sigma_rgb_init), "t_sigma_rgb_init must be finite and > 0");
  check(finite_positive(t_sigma_rgb_min), "t_sigma_rgb_min must be finite and > 0");
  check(finite_positive(t_sigma_icp_m), "t_sigma_icp_m must be finite and > 0");
  check(std::isfinite(rgb_weight) && rgb_weight >= 0.0f, "rgb_weight must be finite and >= 0");
  check(std::isfinite(min_gradient) && min_gradient >= 0.0f, "min_gradient must be finite and >= 0");
  check(std::isfinite(verify_motion_m) && verify_motion_m >= 0.0, "verify_motion_m must be finite and >= 0");
  check(std::isfinite(verify_motion_deg) && verify_motion_deg >= 0.0, "verify_motion_deg must be finite and >= 0");
  check(finite_positive(verify_agreement_m), "verify_agreement_m must be finite and > 0");
  check(finite_positive(verify_agreement_deg), "verify_agreement_deg must be finite and > 0");
  check(finest_level_photometric_step >= 1 && finest_level_photometric_step <= 16,
        "finest_level_photometric_step must be in 1..16");
  check(std::isfinite(degeneracy_threshold) && degeneracy_threshold >= 0.0 && degeneracy_threshold < 1.0,
        "degeneracy_threshold must be in [0, 1)");
  check(min_inliers >= 6, "min_inliers must be >= 6 (six unknowns)");
  check(std::isfinite(poor_inlier_ratio) && poor_inlier_ratio >= 0.0 && poor_inlier_ratio <= 1.0,
        "poor_inlier_ratio must be in [0, 1]");
  check(finite_positive(max_translation_m), "max_translation_m must be finite and > 0");
  check(finite_positive(max_rotation_deg), "max_rotation_deg must be finite and > 0");
  check(finite_positive(max_final_step_translation_m), "max_final_step_translation_m must be finite and > 0");
  check(finite_positive(max_final_step_rotation_rad), "max_final_step_rotation_rad must be finite and > 0");
}

RegistrationOptions default_registration_options(const std::string& name) { return find(name).defaults(); }

std::unique_ptr<Registration> make_registration(const std::string& name, const std::string& backend) {
  const Entry& e = find(name);
  return e.make(e.defaults(), make_backend(backend));
}

std::unique_ptr<Registration> make_registration(const std::string& name, const RegistrationOptions& options,
                                                std::unique_ptr<ReductionBackend> backend) {
  return find(name).make(options, std::move(backend));
}

std::vector<std::string> registration_names() {
  std::vector<std::string> names;
  for (const Entry& e : kMethods) names.emplace_back(e.name);
  return names;
}

}  // namespace hf
