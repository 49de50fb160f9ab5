// Accuracy of every registered method on known motions of the `room` preset (report section 3.1-3.3), and the
// same answer from every backend: each case ranges over registration_names() x backend_names(), so a new method
// is tested by being registered (Open3D's PermuteDevices idea). The "cpu-scalar" backend is the cpu backend with
// its AVX2 paths off: a method's eight-lane spelling and its kernel must agree.
#include <gtest/gtest.h>

#include "core/error.h"
#include "reg_test_util.h"
#include "registration/cpu_backend.h"

namespace hf {
namespace {

std::vector<std::string> backends_under_test() {
  std::vector<std::string> names = backend_names();
  names.push_back("cpu-scalar");
  return names;
}

// The backend, or null (with the reason) where it cannot be created here (opencl without a platform).
std::unique_ptr<ReductionBackend> backend_or_null(const std::string& name, std::string* why) {
  if (name == "cpu-scalar") return std::make_unique<CpuReductionBackend>(8, /*vectorised=*/false);
  try {
    return make_backend(name);
  } catch (const Error& e) {
    *why = e.what();
    return nullptr;
  }
}

const test::FramePair& accuracy_room_pair(bool noise) {
  // Noise-free data without the bilateral filter (it would only smooth creases); noisy data with it, as in use.
  static const test::FramePair clean = test::make_pair("room", 10, 11, false, 3, /*bilateral=*/false);
  static const test::FramePair noisy = test::make_pair("room", 10, 11, true, 3, /*bilateral=*/true);
  return noise ? noisy : clean;
}

RegistrationResult align_on(const std::string& method, const std::string& backend, const test::FramePair& pair) {
  std::string why;
  std::unique_ptr<ReductionBackend> b = backend_or_null(backend, &why);
  if (!b) return RegistrationResult{};
  return make_registration(method, default_registration_options(method), std::move(b))
      ->align(pair.current, pair.reference, SE3());
}

using MethodBackend = std::tuple<std::string, std::string>;
class RoomAccuracy : public ::testing::TestWithParam<MethodBackend> {};

// Noise-free: every method recovers the motion to 0.5 mm / 0.02 deg (the data are exact up to float rounding and
// the projective association's pixel quantisation; the motion is ~10 mm / 0.4 deg). Noisy (Kinect depth noise,
// colour noise): 3 mm / 0.2 deg, the class of the noise's effect on 76800 rows, for the methods with geometric
// rows; photometric alone is held to the looser 5 mm / 0.3 deg (DVO's first-order image model on noisy colour).
TEST_P(RoomAccuracy, RecoversKnownMotionOnEveryBackend) {
  const auto& [method, backend] = GetParam();
  std::string why;
  if (!backend_or_null(backend, &why)) GTEST_SKIP() << backend << " backend unavailable here: " << why;
  for (const bool noise : {false, true}) {
    const test::FramePair& pair = accuracy_room_pair(noise);
    const RegistrationResult r = align_on(method, backend, pair);
    test::expect_finite(r);
    const double et = test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true);
    const double er = test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true);
    std::printf("%s/%s noise=%d: status %s, error %.4f mm %.5f deg (motion %.1f mm %.3f deg), inliers %.3f\n",
                method.c_str(), backend.c_str(), int(noise), to_string(r.status), et * 1e3, er,
                pair.T_ref_cur_true.translation().norm() * 1e3,
                pair.T_ref_cur_true.angle_rad() * 180 / std::numbers::pi, r.inlier_ratio);
    EXPECT_EQ(r.status, RegistrationStatus::good) << r.message;
    const bool photometric_only = method == "photometric";
    // sparse's floor is keypoint localisation, not the data: FAST corners on the integer grid of their ORB level
    // (+-0.5 px x 1.2^octave) over ~180 inliers leave ~0.05 deg even on exact data; it is held to the noisy bound.
    const bool keypoints = method == "sparse";
    // ndt-d2d's floor is its cells: the two frames' grids cut the surfaces differently, and the means of curved
    // patches sit off the surface by different amounts (2.4 mm / 0.09 deg on exact data); photometric's bound.
    // mrsmap's surfels are the same cells (3.1 mm / 0.11 deg on exact data).
    const bool cells = method == "ndt-d2d" || method == "mrsmap";
    EXPECT_LT(et, !noise && !keypoints && !cells ? 0.5e-3 : photometric_only || cells ? 5e-3 : 3e-3) << "noise " << noise;
    EXPECT_LT(er, !noise && !keypoints && !cells ? 0.02 : photometric_only || cells ? 0.3 : 0.2) << "noise " << noise;
  }
}

// Every backend gives the cpu backend's answer: the rows are the same maths (shared kernel headers, no FMA
// contraction), the sums differ only in the order of the double additions (1e-12 relative per reduction), which
// moves the solution by ~1e-9; 1e-6 m / 1e-4 deg leaves room for an accept/reject decision flipping at a gate.
TEST_P(RoomAccuracy, SameAnswerAsTheCpuBackend) {
  const auto& [method, backend] = GetParam();
  if (backend == "cpu") GTEST_SKIP() << "the reference";
  std::string why;
  if (!backend_or_null(backend, &why)) GTEST_SKIP() << backend << " backend unavailable here: " << why;
  const test::FramePair& pair = accuracy_room_pair(true);
  const RegistrationResult ref = align_on(method, "cpu", pair);
  const RegistrationResult got = align_on(method, backend, pair);
  EXPECT_EQ(got.status, ref.status) << got.message;
  EXPECT_EQ(got.iterations_per_level, ref.iterations_per_level);
  EXPECT_NEAR(double(got.inliers), double(ref.inliers), 1e-4 * double(ref.inliers) + 1.0);
  EXPECT_LT(test::translation_error_m(got.T_ref_cur, ref.T_ref_cur), 1e-6);
  EXPECT_LT(test::rotation_error_deg(got.T_ref_cur, ref.T_ref_cur), 1e-4);
}

INSTANTIATE_TEST_SUITE_P(Registry, RoomAccuracy,
                         ::testing::Combine(::testing::ValuesIn(registration_names()),
                                            ::testing::ValuesIn(backends_under_test())),
                         [](const auto& info) {
                           std::string name = std::get<0>(info.param) + "_" + std::get<1>(info.param);
                           for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name;
                         });

}  // namespace
}  // namespace hf
