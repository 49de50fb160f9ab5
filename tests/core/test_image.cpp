#include "core/image.h"

#include <gtest/gtest.h>

namespace hf {
namespace {

TEST(Image, RowMajorStorageAndFill) {
  Image<float> img(4, 3, 0.5f);
  EXPECT_EQ(img.size(), 12u);
  EXPECT_FALSE(img.empty());
  img(3, 2) = 7.0f;
  img(1, 0) = 2.0f;
  EXPECT_EQ(img.data()[2 * 4 + 3], 7.0f);
  EXPECT_EQ(img.data()[1], 2.0f);
  EXPECT_EQ(img(0, 0), 0.5f);
  EXPECT_TRUE(Image<float>().empty());
  static_assert(alignof(hf_float4) == 16 && sizeof(hf_float4) == 16, "hf_float4 must match OpenCL float4");
}

TEST(Image, IntensityFromColorUsesBt601) {
  ColorImage c(4, 1);
  c(0, 0) = {255, 255, 255};
  c(1, 0) = {0, 0, 0};
  c(2, 0) = {255, 0, 0};
  c(3, 0) = {0, 0, 255};
  const IntensityImage i = intensity_from_color(c);
  ASSERT_EQ(i.width(), 4);
  EXPECT_NEAR(i(0, 0), 1.0f, 1e-6f);
  EXPECT_EQ(i(1, 0), 0.0f);
  EXPECT_NEAR(i(2, 0), 0.299f, 1e-6f);
  EXPECT_NEAR(i(3, 0), 0.114f, 1e-6f);
}

}  // namespace
}  // namespace hf
