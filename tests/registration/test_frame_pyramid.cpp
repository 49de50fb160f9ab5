#include "registration/frame_pyramid.h"

#include <gtest/gtest.h>

#include <limits>

#include "core/error.h"

namespace hf {
namespace {

TEST(FramePyramid, LevelsHaveScaledCamerasAndMaps) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);  // 160x120
  DepthImage depth(cam.width, cam.height, 2.0f);
  ColorImage color(cam.width, cam.height, Rgb8{100, 150, 200});
  const FramePyramid p = build_frame_pyramid(depth, &color, cam);
  ASSERT_EQ(p.num_levels(), 3);
  for (int l = 0; l < 3; ++l) {
    const FramePyramidLevel& level = p.levels[size_t(l)];
    EXPECT_EQ(level.camera, cam.scaled(l));
    EXPECT_EQ(level.vertices.width(), level.camera.width);
    EXPECT_EQ(level.normals.height(), level.camera.height);
    EXPECT_EQ(level.grad_x.width(), level.camera.width);
    // A fronto-parallel plane at 2 m: vertices at z = 2, normals (0, 0, -1).
    const hf_float4 v = level.vertices(level.width() / 2, level.height() / 2);
    const hf_float4 n = level.normals(level.width() / 2, level.height() / 2);
    EXPECT_FLOAT_EQ(v.w, 1.0f);
    EXPECT_NEAR(v.z, 2.0f, 1e-5f);
    EXPECT_NEAR(n.z, -1.0f, 1e-5f);
  }
  EXPECT_TRUE(p.has_intensity());
}

TEST(FramePyramid, NanDepthGivesInvalidMapsNotErrors) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);
  DepthImage depth(cam.width, cam.height, std::numeric_limits<float>::quiet_NaN());
  const FramePyramid p = build_frame_pyramid(depth, nullptr, cam);
  for (const hf_float4& v : p.levels[0].vertices.pixels()) EXPECT_EQ(v.w, 0.0f);
  EXPECT_FALSE(p.has_intensity());
}

TEST(FramePyramid, RejectsMismatchedSizes) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);
  DepthImage depth(10, 10, 1.0f);
  EXPECT_THROW(build_frame_pyramid(depth, nullptr, cam), Error);
  FramePyramidOptions o;
  o.levels = 0;
  EXPECT_THROW(build_frame_pyramid(DepthImage(cam.width, cam.height, 1.0f), nullptr, cam, o), Error);
}

TEST(FramePyramid, FillHolesLevelsFillsOnlySmallHolesOfTheTrackingDepth) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);  // 160x120
  DepthImage depth(cam.width, cam.height, 1.5f);
  for (int y = 40; y < 42; ++y)
    for (int x = 60; x < 62; ++x) depth(x, y) = 0.0f;  // a 2x2 hole inside one aligned 4x4 block
  for (int y = 80; y < 112; ++y)
    for (int x = 96; x < 128; ++x) depth(x, y) = 0.0f;  // a 32x32 hole: wider than 2^2
  FramePyramidOptions o;
  o.bilateral_filter = false;
  EXPECT_EQ(build_frame_pyramid(depth, nullptr, cam, o).levels[0].vertices(60, 40).w, 0.0f);  // off by default
  o.fill_holes_levels = 2;
  const FramePyramid p = build_frame_pyramid(depth, nullptr, cam, o);
  EXPECT_EQ(p.levels[0].vertices(60, 40).w, 1.0f);
  EXPECT_FLOAT_EQ(p.levels[0].vertices(61, 41).z, 1.5f);
  EXPECT_EQ(p.levels[0].vertices(112, 96).w, 0.0f);
  o.fill_holes_levels = 9;
  EXPECT_THROW(build_frame_pyramid(depth, nullptr, cam, o), Error);
}

TEST(FramePyramid, ModelPyramidKeepsLevelZeroMaps) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);
  const FramePyramid f = build_frame_pyramid(DepthImage(cam.width, cam.height, 1.5f), nullptr, cam);
  const FramePyramid m = build_model_pyramid(f.levels[0].vertices, f.levels[0].normals, nullptr, cam, 3);
  ASSERT_EQ(m.num_levels(), 3);
  EXPECT_EQ(m.levels[0].vertices.pixels().size(), f.levels[0].vertices.pixels().size());
  EXPECT_NEAR(m.levels[2].vertices(10, 10).z, 1.5f, 1e-5f);
}

}  // namespace
}  // namespace hf
