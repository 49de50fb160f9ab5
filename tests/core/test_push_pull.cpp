// Push-pull fill (core/push_pull.h) and its OpenCL path (core/opencl/push_pull_opencl.h) on analytic cases:
// a fully sampled image is returned unchanged, a constant image with holes is filled with the constant, the two
// paths agree, bad input gives a status and never a NaN.
#include "core/push_pull.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <vector>

#include "core/opencl/push_pull_opencl.h"
#include "core/opencl/opencl_context.h"

namespace hf {
namespace {

struct Sampled {
  int width = 0, height = 0, channels = 1;
  std::vector<float> values;
  std::vector<std::uint8_t> mask;
};

// Random values in [0.1, 1.1) and a mask that keeps each pixel with probability `coverage`, seeded.
Sampled random_sampled(int width, int height, int channels, double coverage, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> value(0.1f, 1.1f);
  std::bernoulli_distribution keep(coverage);
  Sampled s{width, height, channels, std::vector<float>(size_t(width) * height * channels),
            std::vector<std::uint8_t>(size_t(width) * height)};
  for (float& v : s.values) v = value(rng);
  for (std::uint8_t& m : s.mask) m = keep(rng) ? 1 : 0;
  return s;
}

PushPullResult fill(Sampled& s, const PushPullOptions& options = {}) {
  return push_pull_fill(s.width, s.height, s.channels, s.values.data(), s.mask.data(), options);
}

void expect_all_finite(const Sampled& s) {
  for (float v : s.values) ASSERT_TRUE(std::isfinite(v));
}

TEST(PushPull, FullySampledImageIsUnchanged) {
  Sampled s = random_sampled(37, 23, 3, 1.0, 1);
  std::fill(s.mask.begin(), s.mask.end(), 1);
  const std::vector<float> before = s.values;
  const PushPullResult r = fill(s);
  EXPECT_EQ(r.status, PushPullStatus::ok);
  EXPECT_EQ(r.levels, 6);  // 37x23 -> 19x12 -> 10x6 -> 5x3 -> 3x2 -> 2x1 -> 1x1
  EXPECT_EQ(r.filled_pixels, 0);
  EXPECT_EQ(r.empty_pixels, 0);
  EXPECT_EQ(s.values, before);  // bit for bit: pull never touches a sample
}

TEST(PushPull, ConstantImageWithHolesIsFilledWithTheConstant) {
  const float c[3] = {0.3f, 1.7f, 42.0f};
  for (double coverage : {0.02, 0.3, 0.9}) {
    Sampled s = random_sampled(61, 45, 3, coverage, 7);
    for (size_t i = 0; i < s.mask.size(); ++i)
      for (int k = 0; k < 3; ++k) s.values[i * 3 + k] = s.mask[i] ? c[k] : -5.0f;
    const PushPullResult r = fill(s);
    ASSERT_EQ(r.status, PushPullStatus::ok);
    EXPECT_EQ(r.empty_pixels, 0);
    // Each level's mean of <= 4 values within relative e of c is within e + 3 FLT_EPSILON of c (three additions,
    // one correctly rounded division), so level 0 is within levels * 3 FLT_EPSILON.
    const double tol = r.levels * 3.0 * FLT_EPSILON;
    for (size_t i = 0; i < s.mask.size(); ++i) {
      ASSERT_EQ(s.mask[i], 1);
      for (int k = 0; k < 3; ++k) ASSERT_NEAR(s.values[i * 3 + k], c[k], tol * c[k]) << i;
    }
  }
}

TEST(PushPull, OneSampleFillsItsBlockUpToMaxLevels) {
  Sampled s{16, 16, 1, std::vector<float>(256, 0.0f), std::vector<std::uint8_t>(256, 0)};
  s.values[5 * 16 + 6] = 2.5f;  // pixel (6, 5): its 4x4 level-2 block is x 4..7, y 4..7
  s.mask[5 * 16 + 6] = 1;
  const PushPullResult r = fill(s, PushPullOptions{2});
  EXPECT_EQ(r.levels, 2);
  EXPECT_EQ(r.filled_pixels, 15);
  EXPECT_EQ(r.empty_pixels, 256 - 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) {
      const bool in_block = x >= 4 && x < 8 && y >= 4 && y < 8;
      EXPECT_EQ(s.mask[y * 16 + x], in_block ? 1 : 0) << x << "," << y;
      EXPECT_EQ(s.values[y * 16 + x], in_block ? 2.5f : 0.0f) << x << "," << y;
    }
}

TEST(PushPull, BadInputGivesAStatusAndNoNaN) {
  // A masked NaN / inf is dropped, the rest filled.
  Sampled s = random_sampled(20, 9, 2, 0.5, 3);
  s.mask[0] = 1;
  s.values[0] = std::numeric_limits<float>::quiet_NaN();
  s.mask[17] = 1;
  s.values[17 * 2 + 1] = std::numeric_limits<float>::infinity();
  PushPullResult r = fill(s);
  EXPECT_EQ(r.status, PushPullStatus::dropped_non_finite);
  EXPECT_EQ(r.dropped_non_finite, 2);
  EXPECT_EQ(r.empty_pixels, 0);
  expect_all_finite(s);

  // No samples (and NaNs under an empty mask): every value 0.
  Sampled none = random_sampled(8, 8, 1, 0.0, 4);
  none.values[3] = std::numeric_limits<float>::quiet_NaN();
  r = fill(none);
  EXPECT_EQ(r.status, PushPullStatus::no_samples);
  EXPECT_EQ(r.empty_pixels, 64);
  for (float v : none.values) EXPECT_EQ(v, 0.0f);

  // 1x1: sampled is the identity, empty is no_samples.
  Sampled one{1, 1, 1, {0.25f}, {1}};
  r = fill(one);
  EXPECT_EQ(r.status, PushPullStatus::ok);
  EXPECT_EQ(r.levels, 0);
  EXPECT_EQ(one.values[0], 0.25f);
  one.mask[0] = 0;
  EXPECT_EQ(fill(one).status, PushPullStatus::no_samples);

  float v = 1.0f;
  std::uint8_t m = 1;
  EXPECT_EQ(push_pull_fill(0, 5, 1, &v, &m).status, PushPullStatus::empty_image);
  EXPECT_EQ(push_pull_fill(1, 1, 1, nullptr, &m).status, PushPullStatus::empty_image);
  EXPECT_EQ(push_pull_fill(1, 1, 5, &v, &m).status, PushPullStatus::bad_channels);
  EXPECT_EQ(push_pull_fill(1, 1, 0, &v, &m).status, PushPullStatus::bad_channels);
}

TEST(PushPull, DepthHolesAreFilledFromValidDepthsOnly) {
  DepthImage depth(9, 7, 1.5f);
  depth(2, 2) = 0.0f;
  depth(3, 2) = std::numeric_limits<float>::quiet_NaN();
  depth(4, 4) = -1.0f;
  const PushPullResult r = push_pull_fill_depth(depth);
  EXPECT_EQ(r.status, PushPullStatus::ok);  // NaN depth is "no measurement", not a dropped sample
  EXPECT_EQ(r.filled_pixels, 3);
  for (float d : depth.pixels()) EXPECT_FLOAT_EQ(d, 1.5f);
}

bool have_opencl() { return !opencl::list_devices().empty(); }

TEST(PushPullOpenCl, AgreesWithCppToFloatRounding) {
  if (!have_opencl()) GTEST_SKIP() << "no OpenCL platform found (install pocl-opencl-icd): OpenCL push-pull not tested";
  opencl::PushPullOpenCl device;
  struct Case {
    int w, h, channels;
    double coverage;
    int max_levels;
  };
  for (const Case& c : {Case{101, 67, 3, 0.1, -1}, Case{64, 64, 1, 0.02, -1}, Case{33, 17, 4, 0.3, 2},
                        Case{1, 1, 1, 1.0, -1}, Case{1, 9, 2, 0.2, -1}}) {
    Sampled cpu = random_sampled(c.w, c.h, c.channels, c.coverage, 11);
    cpu.values[0] = std::numeric_limits<float>::quiet_NaN();
    Sampled gpu = cpu;
    const PushPullResult rc = fill(cpu, PushPullOptions{c.max_levels});
    const PushPullResult rg = device.fill(gpu.width, gpu.height, gpu.channels, gpu.values.data(), gpu.mask.data(),
                                          PushPullOptions{c.max_levels});
    EXPECT_EQ(rg.status, rc.status);
    EXPECT_EQ(rg.levels, rc.levels);
    EXPECT_EQ(rg.filled_pixels, rc.filled_pixels);
    EXPECT_EQ(rg.empty_pixels, rc.empty_pixels);
    EXPECT_EQ(rg.dropped_non_finite, rc.dropped_non_finite);
    EXPECT_EQ(gpu.mask, cpu.mask);
    for (size_t i = 0; i < cpu.values.size(); ++i)
      ASSERT_NEAR(gpu.values[i], cpu.values[i], 1e-6 * std::fabs(cpu.values[i])) << c.w << "x" << c.h << " " << i;
    expect_all_finite(gpu);
  }
  Sampled none = random_sampled(5, 5, 1, 0.0, 2);
  EXPECT_EQ(device.fill(5, 5, 1, none.values.data(), none.mask.data()).status, PushPullStatus::no_samples);
}

}  // namespace
}  // namespace hf
