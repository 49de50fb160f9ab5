// Quasi-random sample patterns (core/sample_patterns.h) and the triangle-mesh reconstruction
// (core/mesh_interpolation.h): exact Halton values, exact coverage, stratification, density following, and
// linear interpolation reproducing a linear image exactly inside the samples' hull.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"
#include "core/mesh_interpolation.h"
#include "core/sample_patterns.h"

namespace hf {
namespace {

TEST(SamplePatterns, HaltonIsTheRadicalInverse) {
  EXPECT_EQ(halton(0, 2), 0.0);
  EXPECT_EQ(halton(1, 2), 0.5);
  EXPECT_EQ(halton(2, 2), 0.25);
  EXPECT_EQ(halton(3, 2), 0.75);
  EXPECT_NEAR(halton(1, 3), 1.0 / 3.0, 1e-15);
  EXPECT_NEAR(halton(5, 3), 7.0 / 9.0, 1e-15);  // 5 = "12" in base 3 -> 0.21 = 2/3 + 1/9
}

TEST(SamplePatterns, HaltonMaskHasTheCoverageAndIsStratified) {
  const std::vector<std::uint8_t> mask = halton_mask(64, 64, 0.25);
  long set = 0;
  for (std::uint8_t m : mask) set += m;
  EXPECT_EQ(set, 1024);
  // Low discrepancy: every 8x8 tile holds close to its share of 16 (independent random pixels would give a
  // standard deviation of ~3.5 per tile, so some of the 64 tiles would leave 16 +- 7).
  for (int ty = 0; ty < 8; ++ty)
    for (int tx = 0; tx < 8; ++tx) {
      int n = 0;
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) n += mask[size_t(ty * 8 + y) * 64 + tx * 8 + x];
      EXPECT_GE(n, 12) << tx << "," << ty;
      EXPECT_LE(n, 20) << tx << "," << ty;
    }
  EXPECT_THROW(halton_mask(0, 4, 0.5), Error);
  EXPECT_THROW(halton_mask(4, 4, 1.5), Error);
}

TEST(SamplePatterns, DensityMaskFollowsTheDensity) {
  const Image<float> density = focus_density(96, 64, 48.0f, 32.0f, 10.0f, 0.1f);
  EXPECT_EQ(density(48, 32), 1.0f);
  EXPECT_NEAR(density(48 + 20, 32), 0.25f, 1e-6f);  // (10 / 20)^2
  EXPECT_EQ(density(0, 0), 0.1f);                   // (10 / 57.7)^2 = 0.03 -> the floor
  const std::vector<std::uint8_t> mask = halton_mask(density);
  long focus = 0, focus_set = 0, far = 0, far_set = 0;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 96; ++x) {
      const float d = density(x, y);
      if (d >= 1.0f) ++focus, focus_set += mask[size_t(y) * 96 + x];
      if (d <= 0.1f) ++far, far_set += mask[size_t(y) * 96 + x];
    }
  EXPECT_EQ(focus_set, focus);  // the region of interest at full rate
  EXPECT_NEAR(double(far_set) / far, 0.1, 0.03);
}

TEST(MeshInterpolation, ReproducesALinearImageInsideTheHull) {
  const int w = 48, h = 40;
  const std::vector<std::uint8_t> pattern = halton_mask(w, h, 0.1);
  std::vector<float> values(size_t(w) * h * 2, -7.0f);
  std::vector<std::uint8_t> mask = pattern;
  auto f = [](int x, int y, int c) { return c == 0 ? 0.5f * x + 0.25f * y + 1.0f : 3.0f - 0.125f * x; };
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x)
      if (mask[size_t(y) * w + x])
        for (int c = 0; c < 2; ++c) values[(size_t(y) * w + x) * 2 + c] = f(x, y, c);
  const MeshInterpolationResult r = mesh_interpolate(w, h, 2, values.data(), mask.data());
  ASSERT_EQ(r.fill.status, PushPullStatus::ok);
  EXPECT_GT(r.triangles, 100);
  EXPECT_GT(r.fill.filled_pixels, long(0.8 * w * h));
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const size_t p = size_t(y) * w + x;
      for (int c = 0; c < 2; ++c) {
        // Linear interpolation is exact for a linear image (to float rounding of values up to ~35).
        if (mask[p]) ASSERT_NEAR(values[p * 2 + c], f(x, y, c), 1e-4f) << x << "," << y;
        else ASSERT_EQ(values[p * 2 + c], 0.0f);
      }
    }
}

TEST(MeshInterpolation, DegenerateInputGivesAStatus) {
  // Three collinear samples: no triangle, the samples kept, nothing else filled.
  std::vector<float> values(25, 0.0f);
  std::vector<std::uint8_t> mask(25, 0);
  for (int x : {0, 2, 4}) mask[size_t(2 * 5 + x)] = 1, values[size_t(2 * 5 + x)] = 1.0f;
  values[0] = std::numeric_limits<float>::quiet_NaN();
  mask[0] = 1;
  const MeshInterpolationResult r = mesh_interpolate(5, 5, 1, values.data(), mask.data());
  EXPECT_EQ(r.fill.status, PushPullStatus::dropped_non_finite);
  EXPECT_EQ(r.triangles, 0);
  EXPECT_EQ(r.fill.empty_pixels, 22);
  for (float v : values) EXPECT_TRUE(std::isfinite(v));
  std::vector<std::uint8_t> none(25, 0);
  EXPECT_EQ(mesh_interpolate(5, 5, 1, values.data(), none.data()).fill.status, PushPullStatus::no_samples);
}

}  // namespace
}  // namespace hf
