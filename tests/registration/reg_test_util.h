// Helpers shared by the registration tests: synthetic frame pairs with exact ground truth.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "datasets/synthetic_sequence.h"
#include "registration/frame_pyramid.h"
#include "registration/gauss_newton.h"
#include "registration/registration.h"

namespace hf::test {

// Two frames of a preset at 320x240 and the true T_ref_cur (reference = frame i, current = frame j).
struct FramePair {
  FramePyramid reference, current;
  SE3 T_ref_cur_true;
};

inline FramePair make_pair(const std::string& preset, int i, int j, bool noise, std::uint64_t seed = 1,
                           bool bilateral = true) {
  datasets::SyntheticOptions o;
  o.preset = preset;
  o.frames = std::max(i, j) + 1;
  o.seed = seed;
  o.camera = PinholeCamera::preset("ros").scaled(1);
  o.noise_enabled = noise;
  const datasets::SyntheticSequence seq(o);
  const datasets::SyntheticFrame a = seq.frame(i), b = seq.frame(j);
  FramePyramidOptions po;
  po.bilateral_filter = bilateral;
  FramePair p;
  p.reference = build_frame_pyramid(a.depth, &a.color, o.camera, po);
  p.current = build_frame_pyramid(b.depth, &b.color, o.camera, po);
  p.T_ref_cur_true = a.T_world_camera.inverse() * b.T_world_camera;
  return p;
}

inline double translation_error_m(const SE3& a, const SE3& b) { return (a.inverse() * b).translation().norm(); }
inline double rotation_error_deg(const SE3& a, const SE3& b) {
  return (a.inverse() * b).angle_rad() * 180.0 / std::numbers::pi;
}

// Every number a result carries is finite.
inline void expect_finite(const RegistrationResult& r) {
  EXPECT_TRUE(r.T_ref_cur.is_finite());
  EXPECT_TRUE(r.information.allFinite());
  EXPECT_TRUE(r.eigenvalues.allFinite());
  EXPECT_TRUE(std::isfinite(r.condition_number));
  EXPECT_TRUE(std::isfinite(r.final_cost));
  EXPECT_TRUE(std::isfinite(r.inlier_ratio));
}

// A registered method and, when it is a per-pixel method on the Gauss-Newton driver, that driver (its kernel and
// level problems); dense == nullptr for a method that implements Registration directly.
struct MethodUnderTest {
  std::unique_ptr<Registration> registration;
  GaussNewtonRegistration* dense = nullptr;
};

inline MethodUnderTest method_under_test(const std::string& name, const RegistrationOptions& options,
                                         std::unique_ptr<ReductionBackend> backend) {
  MethodUnderTest m;
  m.registration = make_registration(name, options, std::move(backend));
  m.dense = dynamic_cast<GaussNewtonRegistration*>(m.registration.get());
  return m;
}

inline MethodUnderTest method_under_test(const std::string& name, const std::string& backend = "cpu") {
  return method_under_test(name, default_registration_options(name), make_backend(backend));
}

// Sets every robust-kernel option of `options` (each term's) to `kernel`.
inline void set_robust_kernels(RegistrationOptions& options, RobustKernel kernel) {
  options.for_each_option([kernel](const char*, auto& field) {
    if constexpr (std::is_same_v<std::remove_reference_t<decltype(field)>, RobustKernel>) field = kernel;
  });
}

inline const char* robust_name(RobustKernel k) {
  return k == RobustKernel::huber ? "huber" : k == RobustKernel::student_t ? "student_t" : "none";
}

}  // namespace hf::test
