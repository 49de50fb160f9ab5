#include "core/filters.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"
#include "core/kernels/image_kernels.h"
#include "tests/core/synthetic.h"

namespace hf {
namespace {

using test::test_camera;

// Effective number of samples of the truncated spatial Gaussian, (sum w)^2 / sum w^2 (~ 4 pi sigma_s^2 = 254
// for the untruncated default).
double effective_neighbours(const BilateralParams& p, int radius) {
  double s = 0.0, s2 = 0.0;
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) {
      const double w = std::exp(-(dx * dx + dy * dy) / (2.0 * p.sigma_s_px * p.sigma_s_px));
      s += w;
      s2 += w * w;
    }
  return s * s / s2;
}

struct Residuals {
  double mean = 0.0, stddev = 0.0;
  long count = 0;
};

Residuals interior_residuals(const DepthImage& d, const DepthImage& truth, int margin) {
  Residuals r;
  double sum = 0.0, sum2 = 0.0;
  for (int y = margin; y < d.height() - margin; ++y)
    for (int x = margin; x < d.width() - margin; ++x) {
      const double e = double(d(x, y)) - truth(x, y);
      sum += e;
      sum2 += e * e;
      ++r.count;
    }
  r.mean = sum / double(r.count);
  r.stddev = std::sqrt(sum2 / double(r.count) - r.mean * r.mean);
  return r;
}

// On a plane with i.i.d. noise sigma_n << sigma_r the range weights are ~1 and the filter is a spatial Gaussian
// average: the noise drops to sigma_n / sqrt(N_eff). The range term also pulls the output towards the (noisy)
// centre by k = sigma_n^2 / (sigma_n^2 + sigma_r^2) of its error, so expected ratio = sqrt(1 / N_eff + k^2).
// The measured std over ~10^4 correlated outputs (about 60 independent windows) is accurate to ~10%: we assert
// it lies within [0.6, 1.5] times the expectation.
TEST(BilateralFilter, ReducesNoiseOnPlaneByExpectedFactor) {
  const PinholeCamera cam = test_camera(2);  // 160x120
  const DepthImage truth = test::render_plane(cam, Eigen::Vector3d(0.1, 0.05, 1.0).normalized(), 1.5);
  DepthImage noisy = truth;
  const double sigma_n = 0.003;
  test::add_depth_noise(noisy, sigma_n, 42);
  const BilateralParams params;
  const int radius = bilateral_radius_px(params);
  ASSERT_EQ(radius, 3);
  const DepthImage filtered = bilateral_filter_depth(noisy, params);
  const Residuals before = interior_residuals(noisy, truth, radius);
  const Residuals after = interior_residuals(filtered, truth, radius);
  const double n_eff = effective_neighbours(params, radius);
  const double k = sigma_n * sigma_n / (sigma_n * sigma_n + double(params.sigma_r_m) * params.sigma_r_m);
  const double expected_ratio = std::sqrt(1.0 / n_eff + k * k);
  const double ratio = after.stddev / before.stddev;
  RecordProperty("noise_ratio", std::to_string(ratio));
  RecordProperty("expected_ratio", std::to_string(expected_ratio));
  EXPECT_NEAR(before.stddev, sigma_n, 0.1 * sigma_n);
  EXPECT_LT(ratio, 1.5 * expected_ratio) << "N_eff = " << n_eff;
  EXPECT_GT(ratio, 0.6 * expected_ratio) << "N_eff = " << n_eff;
  // No bias: the mean residual is within 3 standard errors of the (filtered) noise.
  EXPECT_LT(std::abs(after.mean), 3.0 * sigma_n * expected_ratio);
}

// A 20 cm step (6.7 sigma_r: cross-edge weight exp(-22) ~ 0) is not moved: pixels on each side stay on their
// own surface. Near the edge only about half the window is on the same side, so the noise bound uses N_eff / 4
// (corners) and 5 standard deviations. A plain Gaussian (huge sigma_r) fails the same check, which shows the
// check can see edge blurring.
TEST(BilateralFilter, PreservesDepthEdge) {
  const int w = 120, h = 90, edge_x = 61;
  DepthImage truth(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) truth(x, y) = x < edge_x ? 1.0f : 1.2f;
  DepthImage noisy = truth;
  const double sigma_n = 0.003;
  test::add_depth_noise(noisy, sigma_n, 5);
  const BilateralParams params;
  const double n_eff = effective_neighbours(params, bilateral_radius_px(params));
  const double bound = 5.0 * sigma_n * std::sqrt(4.0 / n_eff) + sigma_n * sigma_n / (0.03 * 0.03) * 5.0 * sigma_n;
  const DepthImage filtered = bilateral_filter_depth(noisy, params);
  double worst = 0.0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) worst = std::max(worst, std::abs(double(filtered(x, y)) - truth(x, y)));
  RecordProperty("worst_edge_error_m", std::to_string(worst));
  EXPECT_LT(worst, bound);

  BilateralParams gaussian = params;
  gaussian.sigma_r_m = 100.0f;
  const DepthImage blurred = bilateral_filter_depth(noisy, gaussian);
  EXPECT_GT(std::abs(double(blurred(edge_x - 1, h / 2)) - 1.0), 0.05) << "a Gaussian blur must smear the edge";
}

TEST(BilateralFilter, InvalidPixelsStayInvalidAndCarryNoWeight) {
  DepthImage d(50, 40, 1.25f);
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float holes[] = {0.0f, nan, inf, -1.0f};
  for (float& v : d.pixels())
    if (u(rng) < 0.3f) v = holes[int(u(rng) * 4.0f) & 3];
  const DepthImage f = bilateral_filter_depth(d);
  for (size_t i = 0; i < d.size(); ++i) {
    const float in = d.data()[i];
    const bool valid = std::isfinite(in) && in > 0.0f;
    // A constant surface stays exactly constant when holes carry no weight (all samples are 1.25).
    // (to the rounding of a 49-term weighted sum, a few ulps of 1.25 = 1.2e-7)
    ASSERT_NEAR(f.data()[i], valid ? 1.25f : 0.0f, 2e-6f) << i;
  }
}

TEST(BilateralFilter, AllInvalidInputGivesAllInvalidOutput) {
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float value : {0.0f, nan, inf, -3.0f}) {
    const DepthImage f = bilateral_filter_depth(DepthImage(40, 30, value));
    for (float v : f.pixels()) ASSERT_EQ(v, 0.0f);
  }
  EXPECT_TRUE(bilateral_filter_depth(DepthImage()).empty());
}

TEST(BilateralFilter, ExplicitRadiusAndBadParams) {
  DepthImage d(20, 20, 1.0f);
  d(10, 10) = 1.01f;
  BilateralParams p;
  p.radius_px = 1;
  const DepthImage f = bilateral_filter_depth(d, p);
  EXPECT_FLOAT_EQ(f(0, 0), 1.0f);  // (10, 10) is outside the 3x3 window of (0, 0)
  EXPECT_GT(f(10, 10), 1.0f);
  EXPECT_LT(f(10, 10), 1.01f);
  for (auto bad : {BilateralParams{0.0f, 0.03f, 0}, BilateralParams{4.5f, -1.0f, 0}, BilateralParams{4.5f, 0.03f, -1},
                   BilateralParams{std::numeric_limits<float>::quiet_NaN(), 0.03f, 0}}) {
    EXPECT_THROW(bilateral_filter_depth(d, bad), Error);
  }
}

// The default window is 7x7; radius_px = 0 still selects ceil(2 sigma_s) = 9 (19x19), and a wider window
// smooths more: on the same noisy plane the 19x19 output is quieter than the 7x7 one.
TEST(BilateralFilter, AutoRadiusIsTwoSigma) {
  BilateralParams p;
  EXPECT_EQ(bilateral_radius_px(p), 3);
  p.radius_px = 0;
  EXPECT_EQ(bilateral_radius_px(p), 9);
  const PinholeCamera cam = test_camera(2);
  const DepthImage truth = test::render_plane(cam, Eigen::Vector3d(0.0, 0.0, 1.0), 1.5);
  DepthImage noisy = truth;
  test::add_depth_noise(noisy, 0.003, 7);
  const double wide = interior_residuals(bilateral_filter_depth(noisy, p), truth, 9).stddev;
  const double narrow = interior_residuals(bilateral_filter_depth(noisy), truth, 9).stddev;
  EXPECT_LT(wide, 0.8 * narrow);
}

// The vectorised CPU loop and the shared per-pixel function (the OpenCL path) compute the same eq. 2: on depth
// with edges, slopes and every kind of hole they agree to float rounding (the polynomial exp is accurate to
// 2e-7 relative; outputs are ~1-3 m, so 1e-5 m is ~10 ulps).
TEST(BilateralFilter, MatchesSharedPixelKernel) {
  const int w = 97, h = 61;
  DepthImage d(w, h);
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  std::normal_distribution<float> noise(0.0f, 0.01f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  const float holes[] = {0.0f, nan, inf, -1.0f};
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      d(x, y) = (x < 40 ? 1.0f + 0.01f * float(y) : 2.5f - 0.005f * float(x)) + noise(rng);
      if (u(rng) < 0.15f) d(x, y) = holes[int(u(rng) * 4.0f) & 3];
    }
  for (const int radius : {1, 3, 0}) {
    BilateralParams p;
    p.radius_px = radius;
    const int r = bilateral_radius_px(p);
    const float iss = 1.0f / (2.0f * p.sigma_s_px * p.sigma_s_px), irr = 1.0f / (2.0f * p.sigma_r_m * p.sigma_r_m);
    const DepthImage f = bilateral_filter_depth(d, p);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        ASSERT_NEAR(f(x, y), hf_bilateral_depth_pixel(d.data(), w, h, x, y, r, iss, irr), 1e-5f)
            << x << "," << y << " radius " << r;
      }
  }
}

TEST(ImageGradients, LinearRampIsExactEverywhere) {
  const int w = 37, h = 23;
  const float a = 0.0125f, b = -0.03125f;  // exact binary fractions
  Image<float> img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img(x, y) = 0.25f + a * float(x) + b * float(y);
  const ImageGradients g = image_gradients(img);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      ASSERT_NEAR(g.dx(x, y), a, 2e-6) << x << "," << y;
      ASSERT_NEAR(g.dy(x, y), b, 2e-6) << x << "," << y;
    }
}

TEST(ImageGradients, DegenerateShapes) {
  Image<float> row(5, 1);
  for (int x = 0; x < 5; ++x) row(x, 0) = float(x);
  const ImageGradients g = image_gradients(row);
  for (int x = 0; x < 5; ++x) {
    EXPECT_FLOAT_EQ(g.dx(x, 0), 1.0f);
    EXPECT_EQ(g.dy(x, 0), 0.0f);
  }
  EXPECT_TRUE(image_gradients(Image<float>()).dx.empty());
  const ImageGradients one = image_gradients(Image<float>(1, 1, 3.0f));
  EXPECT_EQ(one.dx(0, 0), 0.0f);
  EXPECT_EQ(one.dy(0, 0), 0.0f);
}

TEST(Bilinear, ReproducesRampInsideAndRejectsOutside) {
  const int w = 9, h = 7;
  Image<float> img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img(x, y) = 1.0f + 0.5f * float(x) - 0.25f * float(y);
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> ux(0.0f, float(w - 1)), uy(0.0f, float(h - 1));
  for (int i = 0; i < 200; ++i) {
    const float x = ux(rng), y = uy(rng);
    const auto v = sample_bilinear(img, x, y);
    ASSERT_TRUE(v.has_value());
    EXPECT_NEAR(*v, 1.0f + 0.5f * x - 0.25f * y, 1e-5f);
  }
  EXPECT_FLOAT_EQ(*sample_bilinear(img, float(w - 1), float(h - 1)), img(w - 1, h - 1));
  EXPECT_FLOAT_EQ(*sample_bilinear(img, 0.0f, 0.0f), img(0, 0));
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (auto [x, y] : {std::pair{-0.01f, 1.0f}, {1.0f, -0.01f}, {float(w - 1) + 0.01f, 1.0f}, {1.0f, float(h) - 0.99f},
                      {nan, 1.0f}, {1.0f, nan}, {1e30f, 1.0f}}) {
    EXPECT_FALSE(sample_bilinear(img, x, y).has_value()) << x << "," << y;
  }
  EXPECT_FALSE(sample_bilinear(Image<float>(), 0.0f, 0.0f).has_value());
  EXPECT_FLOAT_EQ(*sample_bilinear(Image<float>(1, 1, 4.0f), 0.0f, 0.0f), 4.0f);
}

TEST(Bilinear, DepthSamplingNeverBlendsHoles) {
  DepthImage d(6, 6, 2.0f);
  d(3, 3) = 0.0f;
  d(4, 1) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_FALSE(sample_depth_bilinear(d, 2.5f, 2.5f).has_value());
  EXPECT_FALSE(sample_depth_bilinear(d, 3.0f, 2.5f).has_value());
  EXPECT_FALSE(sample_depth_bilinear(d, 3.5f, 1.0f).has_value());
  // At exactly integer coordinates the hole next door has zero weight.
  EXPECT_FLOAT_EQ(*sample_depth_bilinear(d, 2.0f, 3.0f), 2.0f);
  EXPECT_FLOAT_EQ(*sample_depth_bilinear(d, 4.0f, 2.0f), 2.0f);
  EXPECT_FLOAT_EQ(*sample_depth_bilinear(d, 0.5f, 0.5f), 2.0f);
  // The plain sampler does blend a zero (it does not know about depth validity).
  EXPECT_FLOAT_EQ(*sample_bilinear(d, 2.5f, 2.5f), 1.5f);
}

}  // namespace
}  // namespace hf
