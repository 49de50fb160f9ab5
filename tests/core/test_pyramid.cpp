#include "core/pyramid.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "core/error.h"
#include "core/kernels/image_kernels.h"
#include "core/normals.h"
#include "tests/core/synthetic.h"

namespace hf {
namespace {

using test::test_camera;

// Level-0 coordinate of the centre of level-l pixel x: inverting c_l = (c + 0.5) / 2^l - 0.5.
double level0_coord(double x_l, int level) { return (x_l + 0.5) * double(1 << level) - 0.5; }

TEST(GaussianPyramid, LinearRampSampledAtBlockCentres) {
  const int w = 64, h = 48;
  const double a = 0.013, b = -0.007, c = 0.4;
  Image<float> ramp(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) ramp(x, y) = float(a * x + b * y + c);
  const auto pyr = build_gaussian_pyramid(ramp, 3);
  ASSERT_EQ(pyr.size(), 3u);
  for (int l = 1; l < 3; ++l) {
    const Image<float>& img = pyr[size_t(l)];
    ASSERT_EQ(img.width(), w >> l);
    ASSERT_EQ(img.height(), h >> l);
    // Away from the clamped border (3 pixels per level) the symmetric kernel reproduces the ramp exactly at the
    // block centre: this is the convention of PinholeCamera::scaled(). A pyrDown centred on 2x would be off by
    // half a level-(l-1) pixel, i.e. by |a| * 2^(l-1) / 2 >= 0.003.
    for (int y = 3; y < img.height() - 3; ++y) {
      for (int x = 3; x < img.width() - 3; ++x) {
        const double expected = a * level0_coord(x, l) + b * level0_coord(y, l) + c;
        ASSERT_NEAR(img(x, y), expected, 1e-5) << "level " << l << " pixel " << x << "," << y;
      }
    }
  }
}

TEST(GaussianPyramid, ConstantImageStaysConstantIncludingBorders) {
  const auto pyr = build_gaussian_pyramid(Image<float>(33, 17, 0.625f), 4);
  ASSERT_EQ(pyr.size(), 4u);
  EXPECT_EQ(pyr[3].width(), 4);
  EXPECT_EQ(pyr[3].height(), 2);
  for (const auto& level : pyr)
    for (float v : level.pixels()) EXPECT_FLOAT_EQ(v, 0.625f);
}

TEST(GaussianPyramid, ImpulseResponseIsTheBinomialKernel) {
  Image<float> img(16, 16, 0.0f);
  img(8, 8) = 1024.0f;
  const Image<float> half = pyr_down_gaussian(img);
  // Level-1 pixels 3..5 see the impulse at taps 8 - (2x - 2) = 4, 2, 0 -> weights 5/32, 10/32 (x=4: tap 2), 1/32.
  const float w[6] = {1, 5, 10, 10, 5, 1};
  for (int y = 0; y < 8; ++y) {
    for (int x = 0; x < 8; ++x) {
      const int ix = 8 - (2 * x - 2), iy = 8 - (2 * y - 2);
      const float expected = (ix >= 0 && ix < 6 && iy >= 0 && iy < 6) ? 1024.0f * w[ix] * w[iy] / 1024.0f : 0.0f;
      EXPECT_FLOAT_EQ(half(x, y), expected) << x << "," << y;
    }
  }
}

// pyr_down_gaussian runs interior pixels eight at a time with AVX2 where the processor has it: every output must
// still be the per-pixel kernel's, bit for bit, for every width remainder and at the borders.
TEST(GaussianPyramid, EveryPixelIsTheKernels) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 2 + int(rng() % 90), h = 2 + int(rng() % 30);
    Image<float> img(w, h);
    for (float& v : img.pixels()) v = 100.0f * u(rng);
    const Image<float> half = pyr_down_gaussian(img);
    for (int y = 0; y < half.height(); ++y)
      for (int x = 0; x < half.width(); ++x) {
        const float expected = hf_pyrdown_gaussian_pixel(img.data(), w, h, x, y);
        ASSERT_EQ(std::memcmp(&half(x, y), &expected, sizeof(float)), 0)
            << "trial " << trial << " (" << w << "x" << h << ") pixel " << x << "," << y;
      }
  }
}

TEST(GaussianPyramid, SizesFollowTheScaledCamera) {
  PinholeCamera cam = PinholeCamera::preset("ros");
  cam.width = 641;
  cam.height = 481;
  const auto pyr = build_gaussian_pyramid(Image<float>(641, 481, 0.5f), 4);
  for (int l = 0; l < 4; ++l) {
    EXPECT_EQ(pyr[size_t(l)].width(), cam.scaled(l).width);
    EXPECT_EQ(pyr[size_t(l)].height(), cam.scaled(l).height);
  }
}

TEST(Pyramid, BadArgumentsThrow) {
  EXPECT_THROW(pyr_down_gaussian(Image<float>(1, 8)), Error);
  EXPECT_THROW(pyr_down_gaussian(Image<float>()), Error);
  EXPECT_THROW(build_gaussian_pyramid(Image<float>(8, 8), 0), Error);
  EXPECT_THROW(build_gaussian_pyramid(Image<float>(8, 8), 5), Error);  // 8 -> 4 -> 2 -> 1 -> cannot halve
  EXPECT_THROW(pyr_down_depth(DepthImage(8, 1)), Error);
  EXPECT_THROW(pyr_down_depth(DepthImage(8, 8), 0.0f), Error);
  EXPECT_THROW(pyr_down_depth(DepthImage(8, 8), std::numeric_limits<float>::quiet_NaN()), Error);
  EXPECT_THROW(build_depth_pyramid(DepthImage(8, 8), -1), Error);
  EXPECT_EQ(build_depth_pyramid(DepthImage(8, 8), 1).size(), 1u);
}

// A tilted plane stays on the plane at every level when back-projected with camera.scaled(level).
// Derived tolerance: with 1/d = a u + b v + c' linear in pixel coordinates, d_uu = 2 a^2 d^3 (likewise v), so a
// symmetric kernel of per-axis variance s^2 biases the depth by ~ (a^2 + b^2) d^3 s^2. The level-1 kernel
// [1 5 10 10 5 1]/32 has s^2 = 1.25 px^2; level l composes them: s_l^2 = 1.25 (4^l - 1) / 3 level-0 px^2. A depth
// error e along the ray is a distance e (n . r) = e dist / d from the plane. Plus float rounding (~4 eps d).
TEST(DepthPyramid, TiltedPlaneStaysOnPlaneWithScaledCamera) {
  const PinholeCamera cam = test_camera(1);  // 320x240
  const Eigen::Vector3d n = Eigen::Vector3d(0.5, 0.3, 1.0).normalized();
  const double dist = 2.0;
  const auto pyr = build_depth_pyramid(test::render_plane(cam, n, dist), 4);
  const double a = n.x() / (cam.fx * dist), b = n.y() / (cam.fy * dist);
  double worst_ratio = 0.0;
  long full_count = 0, truncated_count = 0;
  for (int l = 1; l < 4; ++l) {
    const PinholeCamera cam_l = cam.scaled(l);
    const DepthImage& d = pyr[size_t(l)];
    ASSERT_EQ(d.width(), cam_l.width);
    const double s2 = 1.25 * (std::pow(4.0, l) - 1.0) / 3.0;
    const int margin = 3;
    for (int y = margin; y < d.height() - margin; ++y) {
      for (int x = margin; x < d.width() - margin; ++x) {
        ASSERT_GT(d(x, y), 0.0f);
        const Eigen::Vector3d p = cam_l.backproject(x, y, d(x, y));
        const double off_plane = std::abs(n.dot(p) - dist);
        const double depth = p.z();
        double tol = 1.5 * (a * a + b * b) * depth * depth * depth * s2 * dist / depth + 4.0 * FLT_EPSILON * depth;
        // Where the plane is so steep that the depth across the last 6x6 window (+-2.5 level-(l-1) pixels, i.e.
        // +-2.5 * 2^(l-1) level-0 pixels) exceeds 3 sigma_r, the acceptance window truncates the kernel, and
        // curvature can make that truncation asymmetric: at most the outer tap column/row (weight 1/32 each) at
        // up to 3 sigma_r, so add 2/32 * 3 sigma_r / (30/32).
        const double slope_m_per_px = (std::abs(a) + std::abs(b)) * depth * depth;
        const bool truncated = slope_m_per_px * 2.5 * double(1 << (l - 1)) > 0.9 * 3.0 * kDepthPyramidSigmaR_m;
        if (truncated) {
          tol += 2.0 / 30.0 * 3.0 * kDepthPyramidSigmaR_m;
          ++truncated_count;
        } else {
          worst_ratio = std::max(worst_ratio, off_plane / tol);
          ++full_count;
        }
        ASSERT_LT(off_plane, tol) << "level " << l << " pixel " << x << "," << y << (truncated ? " (truncated)" : "");
      }
    }
    // The same samples with the wrong convention (centre at 2x, i.e. c_l = c / 2^l) are far off the plane.
    PinholeCamera wrong = cam_l;
    wrong.cx = cam.cx / double(1 << l);
    wrong.cy = cam.cy / double(1 << l);
    const Eigen::Vector3d q = wrong.backproject(d.width() / 2, d.height() / 2, d(d.width() / 2, d.height() / 2));
    EXPECT_GT(std::abs(n.dot(q) - dist), 1e-3) << "level " << l;
  }
  RecordProperty("worst_error_over_tolerance", std::to_string(worst_ratio));
  EXPECT_GT(full_count, 5 * truncated_count) << "the strict bound must cover most pixels";
}

// Level-1 vertices of a plane, computed with the level-1 camera, lie on the plane (spec: level-camera check).
TEST(DepthPyramid, LevelOneVertexMapLiesOnPlane) {
  const PinholeCamera cam = test_camera(0);
  const Eigen::Vector3d n = Eigen::Vector3d(-0.3, 0.4, 1.0).normalized();
  const double dist = 1.2;
  const auto pyr = build_depth_pyramid(test::render_plane(cam, n, dist), 2);
  const VertexMap vm = compute_vertex_map(pyr[1], cam.scaled(1));
  double worst = 0.0;
  for (int y = 3; y < vm.height() - 3; ++y)
    for (int x = 3; x < vm.width() - 3; ++x) {
      ASSERT_EQ(vm(x, y).w, 1.0f);
      worst = std::max(worst, std::abs(n.dot(Eigen::Vector3d(vm(x, y).x, vm(x, y).y, vm(x, y).z)) - dist));
    }
  // Curvature bias (see above) is ~1e-6 m here; float rounding ~3e-7 m. Half a level-0 pixel of shift would be
  // ~1e-3 m.
  EXPECT_LT(worst, 2e-5);
}

// Foreground disc at 1.0 m over a background at 1.5 m: every level-1 and level-2 value is one or the other,
// never a blend, whichever way the edge cuts the 2x2 blocks.
TEST(DepthPyramid, DoesNotMixForegroundAndBackground) {
  const int w = 96, h = 64;
  DepthImage d(w, h, 1.5f);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if ((x - 45.3) * (x - 45.3) + (y - 30.7) * (y - 30.7) < 19.0 * 19.0) d(x, y) = 1.0f;
  for (int y = 0; y < h; ++y) d(70, y) = 1.0f;  // a 1-pixel foreground line on an odd and...
  for (int y = 0; y < h; ++y) d(81, y) = 1.0f;  // ... an even/odd block boundary
  const auto pyr = build_depth_pyramid(d, 3);
  int fg = 0, bg = 0;
  for (int l = 1; l < 3; ++l) {
    for (float v : pyr[size_t(l)].pixels()) {
      const bool is_fg = std::abs(v - 1.0f) < 1e-6f, is_bg = std::abs(v - 1.5f) < 1e-6f;
      ASSERT_TRUE(is_fg || is_bg) << "blended value " << v << " at level " << l;
      fg += is_fg;
      bg += is_bg;
    }
  }
  EXPECT_GT(fg, 100);
  EXPECT_GT(bg, 100);
}

TEST(DepthPyramid, NoisyEdgeKeepsBothSidesWithinNoise) {
  const int w = 64, h = 48;
  DepthImage d(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) d(x, y) = x < 33 ? 1.0f : 1.2f;  // 20 cm step > 3 sigma_r = 9 cm
  test::add_depth_noise(d, 0.005, 7);
  const DepthImage half = pyr_down_depth(d);
  for (int y = 0; y < half.height(); ++y)
    for (int x = 0; x < half.width(); ++x) {
      const float v = half(x, y);
      // 5 sigma of noise; a blend would land ~ 5 to 15 cm off both surfaces.
      ASSERT_TRUE(std::abs(v - 1.0f) < 0.025f || std::abs(v - 1.2f) < 0.025f) << x << "," << y << ": " << v;
    }
}

TEST(DepthPyramid, InvalidNeighboursIgnoredAndOutlierRejected) {
  DepthImage d(40, 30, 2.0f);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float holes[] = {0.0f, nan, inf, -0.5f};
  for (float& v : d.pixels())
    if (u(rng) < 0.4f) v = holes[int(u(rng) * 4.0f) & 3];
  // A block with three valid pixels and a near outlier: the lower median is a 2.0 pixel.
  d(10, 10) = 0.5f;
  d(11, 10) = 2.0f;
  d(10, 11) = 2.0f;
  d(11, 11) = 2.0f;
  // A fully invalid block.
  d(20, 20) = d(21, 20) = d(20, 21) = d(21, 21) = 0.0f;
  const DepthImage half = pyr_down_depth(d);
  for (int y = 0; y < half.height(); ++y)
    for (int x = 0; x < half.width(); ++x) {
      bool any = false;
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) any |= d(2 * x + dx, 2 * y + dy) > 0.0f && std::isfinite(d(2 * x + dx, 2 * y + dy));
      // Valid outputs average only 2.0 samples (the 0.5 outlier of block (5, 5) is never the reference and is
      // more than 3 sigma_r from every reference), so they are exactly 2.0; fully invalid blocks give 0.
      ASSERT_EQ(half(x, y), any ? 2.0f : 0.0f) << x << "," << y;
    }
  EXPECT_EQ(half(10, 10), 0.0f);
}

// pyr_down_depth runs interior pixels eight at a time with AVX2 where the processor has it: every output must
// still be the per-pixel kernel's, bit for bit, on images of every width remainder with holes, outliers, depth
// steps at the 3 sigma_r limit and blocks with 0-4 valid samples.
TEST(DepthPyramid, EveryPixelIsTheKernels) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (int trial = 0; trial < 40; ++trial) {
    const int w = 2 + int(rng() % 90), h = 2 + int(rng() % 30);
    DepthImage d(w, h);
    const float hole_rate = 0.5f * u(rng);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const float surface = (x + y) % 17 < 8 ? 1.0f : 1.0f + 0.2f * u(rng);  // steps near and beyond 9 cm
        const float holes[] = {0.0f, nan, inf, -0.5f};
        d(x, y) = u(rng) < hole_rate ? holes[rng() % 4] : surface + 0.01f * u(rng);
      }
    const float sigma_r = 0.01f + 0.04f * u(rng);
    const DepthImage half = pyr_down_depth(d, sigma_r);
    for (int y = 0; y < half.height(); ++y)
      for (int x = 0; x < half.width(); ++x) {
        const float expected = hf_pyrdown_depth_pixel(d.data(), w, h, x, y, 3.0f * sigma_r);
        ASSERT_EQ(std::memcmp(&half(x, y), &expected, sizeof(float)), 0)
            << "trial " << trial << " (" << w << "x" << h << ") pixel " << x << "," << y << ": " << half(x, y)
            << " vs " << expected;
      }
  }
}

TEST(DepthPyramid, AllInvalidInputsGiveAllInvalidLevels) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float value : {0.0f, nan, inf, -2.0f}) {
    const auto pyr = build_depth_pyramid(DepthImage(64, 48, value), 4);
    for (size_t l = 1; l < pyr.size(); ++l)
      for (float v : pyr[l].pixels()) ASSERT_EQ(v, 0.0f) << "level " << l;
  }
}

}  // namespace
}  // namespace hf
