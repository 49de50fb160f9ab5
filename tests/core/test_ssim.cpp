// SSIM (core/ssim.h) against closed forms: identical images, two constants (luminance term only), and
// checkerboards whose local Gaussian moments are constant to 2e-8 (the 11-tap window's alternating sum squared).
#include "core/ssim.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

namespace hf {
namespace {

Image<float> checkerboard(int w, int h, float mean, float amplitude) {
  Image<float> img(w, h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) img(x, y) = mean + (((x + y) % 2) ? amplitude : -amplitude);
  return img;
}

TEST(Ssim, IdenticalImagesGiveOne) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  Image<float> x(40, 31);
  for (float& v : x.pixels()) v = u(rng);
  const SsimResult r = ssim(x, x);
  EXPECT_EQ(r.status, SsimStatus::ok);
  EXPECT_EQ(r.windows, 30L * 21L);
  EXPECT_NEAR(r.mssim, 1.0, 1e-12);
}

TEST(Ssim, TwoConstantsGiveTheLuminanceTerm) {
  const double a = 0.2, b = 0.7, C1 = 0.01 * 0.01;
  const SsimResult r = ssim(Image<float>(16, 12, float(a)), Image<float>(16, 12, float(b)));
  // Float inputs: a and b are known to ~1e-8, so is the closed form.
  const double fa = float(a), fb = float(b);
  EXPECT_NEAR(r.mssim, (2 * fa * fb + C1) / (fa * fa + fb * fb + C1), 1e-12);
}

TEST(Ssim, CheckerboardsGiveTheContrastStructureTerm) {
  // y = mu + k A s against x = mu + A s (s = +-1 alternating): equal means, sigma_xy = k A^2, sigma_y^2 = k^2 A^2,
  // so SSIM = (2 k A^2 + C2) / ((1 + k^2) A^2 + C2), up to the window's 2e-8 alternating-sum leak.
  const double A = 0.1, mu = 0.5, C2 = 0.03 * 0.03;
  for (double k : {-1.0, 0.5, 2.0}) {
    const SsimResult r = ssim(checkerboard(24, 20, float(mu), float(A)), checkerboard(24, 20, float(mu), float(k * A)));
    const double expected = (2 * k * A * A + C2) / ((1 + k * k) * A * A + C2);
    EXPECT_NEAR(r.mssim, expected, 1e-6) << "k = " << k;
  }
}

TEST(Ssim, BadInputGivesAStatus) {
  EXPECT_EQ(ssim(Image<float>(12, 12), Image<float>(12, 13)).status, SsimStatus::size_mismatch);
  EXPECT_EQ(ssim(Image<float>(10, 40), Image<float>(10, 40)).status, SsimStatus::too_small);
  Image<float> nan(12, 12, 0.5f);
  nan(3, 4) = std::numeric_limits<float>::quiet_NaN();
  const SsimResult r = ssim(nan, Image<float>(12, 12, 0.5f));
  EXPECT_EQ(r.status, SsimStatus::non_finite);
  EXPECT_EQ(r.mssim, 0.0);
  EXPECT_EQ(ssim(ColorImage(11, 11), ColorImage(11, 11)).mssim, 1.0);
}

}  // namespace
}  // namespace hf
