#include "registration/so3_prealign.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>

#include "core/camera.h"
#include "registration/frame_pyramid.h"

namespace hf {
namespace {

// A scene far away: its colour depends on the viewing direction alone (world frame = the reference camera), so two
// views related by a pure rotation R_ref_cur see exactly the homography K R K^-1 that so3_prealign fits.
double so3_test_texture(const Eigen::Vector3d& d) {
  return 0.5 + 0.2 * std::sin(6.0 * d.x()) * std::cos(5.0 * d.y()) + 0.15 * std::sin(4.0 * d.z() + 3.0 * d.x());
}

FramePyramid so3_test_view(const PinholeCamera& cam, const Eigen::Matrix3d& R_ref_cam, bool blank) {
  DepthImage depth(cam.width, cam.height, 2.0f);
  ColorImage color(cam.width, cam.height);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector3d d = (R_ref_cam * cam.backproject(u, v, 1.0)).normalized();
      const auto g = std::uint8_t(std::lround(255.0 * (blank ? 0.5 : so3_test_texture(d))));
      color(u, v) = Rgb8{g, g, g};
    }
  return build_frame_pyramid(depth, &color, cam, {});
}

double so3_test_angle_deg(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  return Eigen::AngleAxisd(a.transpose() * b).angle() * 180.0 / M_PI;
}

// 10 degrees (about 46 px at 320x240: beyond a dense photometric term's basin) is recovered from the identity. The
// bound: a quarter pixel of the finest level used (160x120, f = 131 px) is 0.11 degrees.
TEST(So3Prealign, RecoversAPureRotationFromFarAway) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  const Eigen::Matrix3d R_true = Eigen::AngleAxisd(10.0 * M_PI / 180.0, Eigen::Vector3d(0.3, 1.0, 0.2).normalized())
                                     .toRotationMatrix();
  const FramePyramid ref = so3_test_view(cam, Eigen::Matrix3d::Identity(), false);
  const FramePyramid cur = so3_test_view(cam, R_true, false);
  const So3PrealignResult r = so3_prealign(cur, ref, Eigen::Matrix3d::Identity(), {10, 5}, 3);
  EXPECT_TRUE(r.accepted);
  EXPECT_LT(r.cost_after, r.cost_before);
  EXPECT_GT(r.pixels, 160 * 120 / 2);
  EXPECT_LT(so3_test_angle_deg(r.R_ref_cur, R_true), 0.11) << "from 10 degrees";
  // Started at the answer, it stays there.
  const So3PrealignResult again = so3_prealign(cur, ref, R_true, {10, 5}, 3);
  EXPECT_LT(so3_test_angle_deg(again.R_ref_cur, R_true), 0.11);
}

// Nothing to fit (a uniform image) or no colour: the initial rotation comes back, not accepted.
TEST(So3Prealign, KeepsTheGuessWithoutTexture) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);
  const Eigen::Matrix3d R0 = Eigen::AngleAxisd(0.05, Eigen::Vector3d::UnitY()).toRotationMatrix();
  const FramePyramid blank = so3_test_view(cam, Eigen::Matrix3d::Identity(), true);
  const So3PrealignResult r = so3_prealign(blank, blank, R0, {10, 5}, 3);
  EXPECT_FALSE(r.accepted);
  EXPECT_EQ(r.R_ref_cur, R0);
  FramePyramid no_colour = build_frame_pyramid(DepthImage(cam.width, cam.height, 2.0f), nullptr, cam, {});
  EXPECT_FALSE(so3_prealign(no_colour, no_colour, R0, {10}, 3).accepted);
  EXPECT_FALSE(so3_prealign(blank, blank, R0, {}, 3).accepted);
}

}  // namespace
}  // namespace hf
