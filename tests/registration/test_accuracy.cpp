// Accuracy of icp, photometric and combined on known motions of the `room` preset (report section 3.1-3.3).
#include <gtest/gtest.h>

#include "reg_test_util.h"

namespace hf {
namespace {

struct Case {
  const char* method;
  bool noise;
  double max_translation_m;
  double max_rotation_deg;
};

class RoomAccuracy : public ::testing::TestWithParam<Case> {};

TEST_P(RoomAccuracy, RecoversKnownMotion) {
  const Case c = GetParam();
  // Noise-free data without the bilateral filter (it would only smooth creases); noisy data with it, as in use.
  const test::FramePair pair = test::make_pair("room", 10, 11, c.noise, 3, /*bilateral=*/c.noise);
  auto reg = make_registration(c.method);
  const RegistrationResult r = reg->align(pair.current, pair.reference, SE3());
  test::expect_finite(r);
  const double et = test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true);
  const double er = test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true);
  std::printf("%s noise=%d: status %s, error %.4f mm %.5f deg (motion %.1f mm %.3f deg), inliers %.3f, it %d/%d/%d\n",
              c.method, int(c.noise), to_string(r.status), et * 1e3, er, pair.T_ref_cur_true.translation().norm() * 1e3,
              pair.T_ref_cur_true.angle_rad() * 180 / std::numbers::pi, r.inlier_ratio, r.iterations_per_level[2],
              r.iterations_per_level[1], r.iterations_per_level[0]);
  EXPECT_EQ(r.status, RegistrationStatus::good) << r.message;
  EXPECT_LT(et, c.max_translation_m);
  EXPECT_LT(er, c.max_rotation_deg);
}

INSTANTIATE_TEST_SUITE_P(Registration, RoomAccuracy,
                         ::testing::Values(Case{"icp", false, 0.5e-3, 0.02}, Case{"photometric", false, 0.5e-3, 0.02},
                                           Case{"combined", false, 0.5e-3, 0.02}, Case{"icp", true, 3e-3, 0.2},
                                           Case{"combined", true, 3e-3, 0.2}),
                         [](const auto& info) {
                           return std::string(info.param.method) + (info.param.noise ? "_noisy" : "_clean");
                         });

}  // namespace
}  // namespace hf
