// Documented outcomes on the synthetic hard cases (datasets/presets.h) and on degenerate input. Every result is
// finite, whatever the input.
#include <gtest/gtest.h>

#include <limits>

#include "reg_test_util.h"

namespace hf {
namespace {

struct Outcome {
  RegistrationResult result;
  double et_m, er_deg;
};

Outcome run(const std::string& method, const test::FramePair& pair, const SE3& guess = SE3()) {
  auto reg = make_registration(method);
  Outcome o{reg->align(pair.current, pair.reference, guess), 0.0, 0.0};
  test::expect_finite(o.result);
  o.et_m = test::translation_error_m(o.result.T_ref_cur, pair.T_ref_cur_true);
  o.er_deg = test::rotation_error_deg(o.result.T_ref_cur, pair.T_ref_cur_true);
  const Vector6d& ev = o.result.eigenvalues;
  std::printf("%-12s %-11s dims %d cond %.3g ratios %.2g %.2g %.2g inliers %.3f error %.3f mm %.4f deg (motion %.1f mm) %s\n",
              method.c_str(), to_string(o.result.status), o.result.degenerate_dims, o.result.condition_number,
              ev(0) / ev(5), ev(1) / ev(5), ev(2) / ev(5),
              o.result.inlier_ratio, o.et_m * 1e3, o.er_deg, pair.T_ref_cur_true.translation().norm() * 1e3,
              o.result.message.c_str());
  return o;
}

// A plane fills the view: depth constrains only the normal translation and the two tilts.
TEST(HardCases, WallIcpIsDegenerateInThreeDirectionsCombinedRecoversThem) {
  const test::FramePair pair = test::make_pair("wall", 5, 6, true);
  const Outcome icp = run("icp", pair);
  EXPECT_EQ(icp.result.status, RegistrationStatus::degenerate);
  EXPECT_EQ(icp.result.degenerate_dims, 3);
  const Outcome combined = run("combined", pair);
  EXPECT_EQ(combined.result.status, RegistrationStatus::good) << combined.result.message;
  EXPECT_EQ(combined.result.degenerate_dims, 0);
  EXPECT_LT(combined.et_m, 3e-3);
  EXPECT_LT(combined.er_deg, 0.2);
}

// Walls, floor and ceiling along x: only noise and perspective constrain the translation along the corridor. It
// is weakly constrained, not unconstrained: its balanced eigenvalue ratio (~5e-3 at 320x240 with sensor noise)
// is 2-3x below well-constrained scenes and ~4x above the noise floor of the wall's free directions, so it is
// not flagged degenerate (threshold 3e-3, GaussNewtonOptions::degeneracy_threshold). The documented
// outcome: icp reports good with a small eigenvalue ratio (below 1e-2) and little information along the axis
// (the camera looks along it: its z axis), and keeps the motion along it at the initial guess; combined recovers
// most of it from the texture (error below a third of the 30 mm motion; 4 mm when every finest-level pixel
// gives a photometric row, 8.5 mm with the default finest_level_photometric_step = 2).
TEST(HardCases, CorridorIsWeaklyConstrainedAlongItsAxisCombinedRecoversIt) {
  const test::FramePair pair = test::make_pair("corridor", 5, 6, true);
  const Outcome icp = run("icp", pair);
  EXPECT_EQ(icp.result.status, RegistrationStatus::good) << icp.result.message;
  EXPECT_EQ(icp.result.degenerate_dims, 0);
  const double ratio = icp.result.eigenvalues(0) / icp.result.eigenvalues(5);
  EXPECT_GT(ratio, make_registration("icp")->options().driver.degeneracy_threshold);
  EXPECT_LT(ratio, 1e-2);
  // The information along the corridor's axis (the camera looks along it: its z axis), relative to the largest
  // eigenvalue: translations are not rescaled in the balanced matrix, so u^T H u with u = (0, 0, 0, 0, 0, 1).
  const double along_axis = icp.result.information(5, 5) / icp.result.eigenvalues(5);
  std::printf("information along the axis / largest eigenvalue: %.3g\n", along_axis);
  EXPECT_LT(along_axis, 0.1);
  EXPECT_GT(icp.et_m, 0.5 * pair.T_ref_cur_true.translation().norm());
  const Outcome combined = run("combined", pair);
  EXPECT_TRUE(combined.result.usable());
  EXPECT_EQ(combined.result.degenerate_dims, 0);
  EXPECT_LT(combined.et_m, pair.T_ref_cur_true.translation().norm() / 3.0);
  EXPECT_LT(combined.er_deg, 0.2);
}

// One uniform colour: photometric alignment has (almost) no gradients and must say so; ICP carries the pose.
TEST(HardCases, TexturelessPhotometricIsFlaggedIcpIsFine) {
  const test::FramePair pair = test::make_pair("textureless", 10, 11, true);
  const Outcome photometric = run("photometric", pair);
  EXPECT_NE(photometric.result.status, RegistrationStatus::good);
  const Outcome icp = run("icp", pair);
  EXPECT_EQ(icp.result.status, RegistrationStatus::good) << icp.result.message;
  EXPECT_LT(icp.et_m, 3e-3);
  EXPECT_LT(icp.er_deg, 0.2);
}

// 15 degrees and 10 cm between frames: either the coarse level pulls the estimate into the basin, or the result
// says failed and returns the initial guess. Never a wild pose. On this pair none of the three converges from
// identity: photometric diverges and combined is still sliding at the finest level (both caught by the outcome
// checks), and icp settles in a false minimum 0.41 m off (78% inliers, lower cost than a correct noisy pair),
// which only the reverse-alignment check of large motions (GaussNewtonOptions::verify_motion_*) exposes. Every
// registered method must do one or the other.
TEST(HardCases, FastMotionConvergesOrFailsCleanly) {
  const test::FramePair pair = test::make_pair("fast", 3, 4, true);
  for (const std::string& method : registration_names()) {
    const Outcome o = run(method, pair);
    if (o.result.status == RegistrationStatus::failed) {
      EXPECT_LT(test::translation_error_m(o.result.T_ref_cur, SE3()), 1e-12) << method;
      EXPECT_LT(test::rotation_error_deg(o.result.T_ref_cur, SE3()), 1e-9) << method;
    } else {
      EXPECT_LT(o.et_m, 0.01) << method << " " << to_string(o.result.status);
      EXPECT_LT(o.er_deg, 0.5) << method << " " << to_string(o.result.status);
    }
  }
}

// The check itself: without it icp reports the false minimum as good (the defect it was added for); with it the
// same pair fails cleanly, and a correct large motion is confirmed, not rejected: started from a guess 70 mm
// and 12 deg away from the truth on the room (a motion the check verifies), icp still converges and stays good.
TEST(HardCases, ReverseAlignmentCheckOfLargeMotions) {
  const test::FramePair fast = test::make_pair("fast", 3, 4, true);
  // With the 1e-3 degeneracy threshold of earlier versions icp settles in a false minimum 0.41 m off on this
  // pair (with 3e-3 it is still sliding and fails on its own): that one the check must catch.
  RegistrationOptions checked = default_registration_options("icp");
  checked.driver.degeneracy_threshold = 1e-3;
  RegistrationOptions unchecked = checked;
  unchecked.driver.verify_motion_m = 1e3;
  unchecked.driver.verify_motion_deg = 1e3;
  const RegistrationResult fooled =
      make_registration("icp", unchecked, make_backend("cpu"))->align(fast.current, fast.reference, SE3());
  EXPECT_TRUE(fooled.usable());
  EXPECT_GT(test::translation_error_m(fooled.T_ref_cur, fast.T_ref_cur_true), 0.1);
  EXPECT_EQ(make_registration("icp", checked, make_backend("cpu"))->align(fast.current, fast.reference, SE3()).status,
            RegistrationStatus::failed);

  const test::FramePair room = test::make_pair("room", 10, 11, true);
  const SE3 offset = SE3::exp((Vector6d() << 0.0, 0.035, 0.0, 0.07, 0.0, 0.0).finished());  // 2 deg, 70 mm
  const SE3 guess = room.T_ref_cur_true * offset;
  const RegistrationResult r = make_registration("icp")->align(room.current, room.reference, guess);
  EXPECT_EQ(r.status, RegistrationStatus::good) << r.message;
  EXPECT_GT(test::translation_error_m(guess, r.T_ref_cur), 0.05);  // the check ran
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, room.T_ref_cur_true), 3e-3);
  EXPECT_LT(test::rotation_error_deg(r.T_ref_cur, room.T_ref_cur_true), 0.2);
}

// 30% of the depth missing in blobs: fewer correspondences, same accuracy class.
TEST(HardCases, HolesKeepAccuracy) {
  const test::FramePair pair = test::make_pair("holes", 10, 11, true);
  for (const std::string method : {"icp", "combined"}) {
    const Outcome o = run(method, pair);
    EXPECT_TRUE(o.result.usable()) << method;
    EXPECT_LT(o.et_m, 3e-3) << method;
    EXPECT_LT(o.er_deg, 0.2) << method;
  }
}

// A global gain change between frames violates brightness constancy; Student-t weights plus geometry keep the
// estimate close.
TEST(HardCases, ExposureChangeWithRobustWeights) {
  const test::FramePair pair = test::make_pair("exposure", 10, 11, true);
  const Outcome photometric = run("photometric", pair);
  EXPECT_TRUE(photometric.result.usable() || photometric.result.status == RegistrationStatus::failed);
  const Outcome combined = run("combined", pair);
  EXPECT_TRUE(combined.result.usable());
  EXPECT_LT(combined.et_m, 5e-3);
  EXPECT_LT(combined.er_deg, 0.3);
}

FramePyramid pyramid_from_depth(float fill, int valid_pixels) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  DepthImage depth(cam.width, cam.height, fill);
  for (int i = 0; i < valid_pixels; ++i) depth(100 + i, 100) = 1.5f;
  ColorImage color(cam.width, cam.height, Rgb8{90, 120, 150});
  return build_frame_pyramid(depth, &color, cam);
}

TEST(HardCases, NoUsableDepthIsNoData) {
  const test::FramePair pair = test::make_pair("room", 0, 1, false);
  const SE3 guess = SE3::exp((Vector6d() << 0.01, 0.0, 0.0, 0.02, 0.0, 0.0).finished());
  for (const std::string& method : registration_names()) {
    for (const float fill : {std::numeric_limits<float>::quiet_NaN(), 0.0f}) {
      for (const int valid : {0, 1}) {
        auto reg = make_registration(method);
        const FramePyramid empty = pyramid_from_depth(fill, valid);
        for (const bool empty_is_current : {true, false}) {
          const RegistrationResult r = empty_is_current ? reg->align(empty, pair.reference, guess)
                                                        : reg->align(pair.current, empty, guess);
          test::expect_finite(r);
          EXPECT_EQ(r.status, RegistrationStatus::no_data) << method << " " << r.message;
          EXPECT_FALSE(r.usable());
          EXPECT_LT(test::translation_error_m(r.T_ref_cur, guess), 1e-12);
          EXPECT_FALSE(r.message.empty());
        }
      }
    }
  }
}

TEST(HardCases, InconsistentInputIsAFailureNotAnException) {
  const test::FramePair pair = test::make_pair("room", 0, 1, false);
  FramePyramid broken = pair.current;
  broken.levels[1].normals = NormalMap(3, 3);
  auto reg = make_registration("icp");
  const RegistrationResult r = reg->align(broken, pair.reference, SE3());
  EXPECT_EQ(r.status, RegistrationStatus::failed);
  FramePyramid no_colour = pair.current;
  for (auto& level : no_colour.levels) level.intensity = IntensityImage();
  EXPECT_EQ(make_registration("photometric")->align(no_colour, pair.reference, SE3()).status,
            RegistrationStatus::no_data);
  const SE3 nan_guess(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::nan(""), 0, 0));
  const RegistrationResult n = reg->align(pair.current, pair.reference, nan_guess);
  EXPECT_EQ(n.status, RegistrationStatus::failed);
  test::expect_finite(n);
}

}  // namespace
}  // namespace hf
