#include "core/undistort.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <string>

#include "core/camera.h"
#include "core/error.h"

namespace hf {
namespace {

// The normalised pinhole point whose distorted image is `xd` (Newton on LensDistortion::distort, numerical
// Jacobian): how a synthetic distorted image is rendered, independently of the remap under test.
Eigen::Vector2d undistort_test_invert(const LensDistortion& d, const Eigen::Vector2d& xd) {
  Eigen::Vector2d x = xd;
  for (int it = 0; it < 30; ++it) {
    const Eigen::Vector2d f = d.distort(x) - xd;
    Eigen::Matrix2d J;
    const double h = 1e-7;
    J.col(0) = (d.distort(x + Eigen::Vector2d(h, 0)) - d.distort(x)) / h;
    J.col(1) = (d.distort(x + Eigen::Vector2d(0, h)) - d.distort(x)) / h;
    x -= J.inverse() * f;
  }
  return x;
}

// The scene: a plane Z = 2 + 0.3 X (metres), in front of it for X < -0.2 a step 0.5 m nearer (a depth edge), and a
// colour that varies smoothly with the ray direction.
double undistort_test_depth(const Eigen::Vector2d& xn) {
  const double z_plane = 2.0 / (1.0 - 0.3 * xn.x());  // t = 2 + 0.3 x t along the ray (x, y, 1) t
  return xn.x() * z_plane < -0.2 ? z_plane - 0.5 : z_plane;
}
Rgb8 undistort_test_colour(const Eigen::Vector2d& xn) {
  return Rgb8{std::uint8_t(std::lround(128.0 + 100.0 * std::sin(4.0 * xn.x()))),
              std::uint8_t(std::lround(128.0 + 100.0 * std::cos(5.0 * xn.y()))), 77};
}

struct UndistortTestImages {
  DepthImage depth;
  ColorImage color;
};

// What the distorted camera stores: each stored pixel sees the ray whose distorted image it is.
UndistortTestImages undistort_test_render(const PinholeCamera& cam) {
  UndistortTestImages im{DepthImage(cam.width, cam.height), ColorImage(cam.width, cam.height)};
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector2d xn =
          undistort_test_invert(cam.distortion, {(u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy});
      im.depth(u, v) = float(undistort_test_depth(xn));
      im.color(u, v) = undistort_test_colour(xn);
    }
  return im;
}

PinholeCamera undistort_test_camera() {
  PinholeCamera cam = PinholeCamera::preset("fr1").scaled(2);  // 160x120: the fr1 lens, a quick test
  EXPECT_FALSE(cam.distortion.none());
  return cam;
}

TEST(Undistort, DistortMatchesOpenCvsEquations) {
  const LensDistortion d{0.1, -0.2, 0.01, -0.02, 0.3};
  const double x = 0.3, y = -0.4, r2 = 0.25;
  const double radial = 1.0 + 0.1 * r2 - 0.2 * r2 * r2 + 0.3 * r2 * r2 * r2;
  const Eigen::Vector2d expected(x * radial + 2 * 0.01 * x * y - 0.02 * (r2 + 2 * x * x),
                                 y * radial + 0.01 * (r2 + 2 * y * y) + 2 * -0.02 * x * y);
  EXPECT_LT((d.distort({x, y}) - expected).norm(), 1e-15);
  EXPECT_TRUE(LensDistortion{}.none());
}

TEST(Undistort, IdentityWithoutDistortion) {
  PinholeCamera cam = PinholeCamera::preset("ros").scaled(2);
  const UndistortTestImages im = undistort_test_render(cam);
  const Undistorter u(cam);
  EXPECT_EQ(u.depth(im.depth).pixels(), im.depth.pixels());
  EXPECT_EQ(u.color(im.color).pixels(), im.color.pixels());
}

// The undistorted images are the pinhole camera's view of the scene: depth within what half a stored pixel of
// nearest-neighbour choice allows, colour within bilinear interpolation's error, and far better than reading the
// distorted images as pinhole ones (which is what the pipeline did before).
TEST(Undistort, RecoversThePinholeView) {
  const PinholeCamera cam = undistort_test_camera();
  const UndistortTestImages stored = undistort_test_render(cam);
  const Undistorter und(cam);
  EXPECT_TRUE(und.camera().distortion.none());
  const DepthImage depth = und.depth(stored.depth);
  const ColorImage color = und.color(stored.color);
  // dZ/dx_n of the plane is 0.6 / (1 - 0.3 x)^2 < 1 over this image (|x| < 0.7); half a stored pixel in each axis
  // is at most 0.71 / fx in x_d, and the fr1 lens magnifies at most 1.3x here: 1 * 0.71 * 1.3 / fx.
  const double depth_tol = 0.71 * 1.3 / cam.fx;
  // Colour: |d2c/du2| <= 100 * 25 / f^2 per pixel^2 (the lens stretches it by less than 2x), so bilinear's error is
  // <= 2 * (1/8) of it; plus 0.5 for the stored image's 8-bit rounding, 0.5 for the blend's rounding, and the
  // weights' 1/255-pixel quantisation times the steepest slope (100 * 5 / f per pixel).
  const double colour_tol = 1.0 + 2.0 * 0.125 * 100.0 * 25.0 / (cam.fx * cam.fx) + 100.0 * 5.0 / cam.fx / 255.0;
  int compared = 0, edge_pixels = 0, unseen = 0;
  double worst_depth = 0.0, worst_colour = 0.0, worst_colour_raw = 0.0, nearest_unseen_r = 1e9;
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      const Eigen::Vector2d xn((u - cam.cx) / cam.fx, (v - cam.cy) / cam.fy);
      const float z = depth(u, v);
      if (z == 0.0f) {
        ++unseen;
        nearest_unseen_r = std::min(nearest_unseen_r, xn.norm());
        continue;
      }
      const double plane = 2.0 / (1.0 - 0.3 * xn.x());
      // Never a blend of the two surfaces: every depth lies on one of them.
      const double to_surface = std::min(std::abs(z - plane), std::abs(z - (plane - 0.5)));
      EXPECT_LT(to_surface, depth_tol) << u << "," << v;
      if (std::abs(xn.x() * plane + 0.2) < 0.05) {  // beside the edge: either surface is right
        ++edge_pixels;
        continue;
      }
      ++compared;
      worst_depth = std::max(worst_depth, std::abs(z - undistort_test_depth(xn)));
      // Colour where the whole bilinear footprint lies in the stored image (the last half pixel is clamped).
      const Eigen::Vector2d xd = cam.distortion.distort(xn);
      const double su = cam.fx * xd.x() + cam.cx, sv = cam.fy * xd.y() + cam.cy;
      if (su < 0.0 || sv < 0.0 || su > cam.width - 1.0 || sv > cam.height - 1.0) continue;
      const Rgb8 want = undistort_test_colour(xn), got = color(u, v), raw = stored.color(u, v);
      worst_colour = std::max({worst_colour, std::abs(double(got.r) - want.r), std::abs(double(got.g) - want.g)});
      worst_colour_raw =
          std::max({worst_colour_raw, std::abs(double(raw.r) - want.r), std::abs(double(raw.g) - want.g)});
    }
  EXPECT_GT(compared, cam.width * cam.height * 8 / 10);
  EXPECT_GT(edge_pixels, 0);
  // fr1's lens images the rays near the border outside the stored frame (its radial factor is 1.075 at the
  // corners): those output pixels have no measurement, and only they: none nearer the centre than the image's
  // half-height (0.43 in normalised units below the principal point).
  EXPECT_GT(unseen, 0);
  EXPECT_LT(unseen, cam.width * cam.height / 10);
  EXPECT_GT(nearest_unseen_r, 0.4);
  EXPECT_LT(worst_depth, depth_tol);
  EXPECT_LE(worst_colour, colour_tol + 1e-9);
  EXPECT_GT(worst_colour_raw, 5.0 * colour_tol);  // the distorted image read as a pinhole one is far off (9 here)
}

TEST(Undistort, RefusesAWrongSize) {
  const PinholeCamera cam = undistort_test_camera();
  const Undistorter und(cam);
  EXPECT_THROW(und.depth(DepthImage(cam.width + 1, cam.height)), Error);
  EXPECT_THROW(und.color(ColorImage(cam.width, cam.height - 1)), Error);
  EXPECT_TRUE(und.color(ColorImage()).empty());
}

}  // namespace
}  // namespace hf
