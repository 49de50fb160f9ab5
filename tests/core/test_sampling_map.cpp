// The flexible pinhole camera's sampling map (core/sampling_map.h) on analytic cases: the inverse undoes the
// forward map to float precision, rates of 1 everywhere are the identity camera, per-region rates are the
// local derivative of the map, straight lines stay connected, folded maps are refused.
#include "core/sampling_map.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <random>

#include "core/error.h"

namespace hf {
namespace {

// 640x480 in 16x12 cells: a 4x4-cell region of interest at full rate, the context at 0.4.
SamplingMap focus_context_map() {
  std::vector<float> rates(16 * 12, 0.4f);
  for (int j = 4; j < 8; ++j)
    for (int i = 6; i < 10; ++i) rates[size_t(j) * 16 + i] = 1.0f;
  return SamplingMap::from_region_rates(640, 480, 16, 12, rates);
}

// Float precision of coordinates up to 640 px: a few units in the last place (ulp(640) = 6.1e-5).
constexpr float kCoordTol = 4.0f * 640.0f * FLT_EPSILON;

TEST(SamplingMap, RegionRatesSetTheCoNUSSizeAndTheLocalRate) {
  const SamplingMap m = focus_context_map();
  // 4 of 16 columns at 1, 12 at 0.4: 640 (4 + 4.8) / 16 = 352; rows 480 (4 + 3.2) / 12 = 288.
  EXPECT_EQ(m.conus_width(), 352);
  EXPECT_EQ(m.conus_height(), 288);
  auto rate_at = [&](float u, float v) {
    MapPoint a, b;
    EXPECT_TRUE(m.distort({u, v}, &a));
    EXPECT_TRUE(m.distort({u + 1.0f, v}, &b));
    return b.u - a.u;
  };
  EXPECT_NEAR(rate_at(300.0f, 200.0f), 1.0f, 1e-4f);  // inside the region of interest
  EXPECT_NEAR(rate_at(20.0f, 20.0f), 0.4f, 1e-4f);    // context corner
}

TEST(SamplingMap, InverseUndoesTheForwardMap) {
  std::mt19937 rng(3);
  const SamplingMap tensor = focus_context_map();
  // A general (non-tensor-product) map: the interior nodes of the tensor map moved by up to 3 px, as the paper's
  // mass-spring construction would.
  std::vector<MapPoint> nodes;
  std::uniform_real_distribution<float> jitter(-3.0f, 3.0f);
  for (int j = 0; j <= 12; ++j)
    for (int i = 0; i <= 16; ++i) {
      MapPoint p = tensor.node(i, j);
      if (i > 0 && i < 16 && j > 0 && j < 12) p = {p.u + jitter(rng), p.v + jitter(rng)};
      nodes.push_back(p);
    }
  const SamplingMap general = SamplingMap::from_nodes(640, 480, 352, 288, 16, 12, nodes);
  for (const SamplingMap* m : {&tensor, &general}) {
    std::uniform_real_distribution<float> u(-0.5f, 639.5f), v(-0.5f, 479.5f);
    std::uniform_real_distribution<float> ud(-0.5f, m->conus_width() - 0.5f), vd(-0.5f, m->conus_height() - 0.5f);
    for (int k = 0; k < 2000; ++k) {
      const MapPoint p{u(rng), v(rng)};
      MapPoint d, back;
      ASSERT_TRUE(m->distort(p, &d));
      ASSERT_TRUE(m->undistort(d, &back));
      ASSERT_NEAR(back.u, p.u, kCoordTol);
      ASSERT_NEAR(back.v, p.v, kCoordTol);
      const MapPoint q{ud(rng), vd(rng)};
      ASSERT_TRUE(m->undistort(q, &back));
      ASSERT_TRUE(m->distort(back, &d));
      ASSERT_NEAR(d.u, q.u, kCoordTol);
      ASSERT_NEAR(d.v, q.v, kCoordTol);
    }
    // rays() (rasterised) agrees with the point query at every CoNUS pixel.
    const std::vector<MapPoint> rays = m->rays();
    for (int y = 0; y < m->conus_height(); y += 7)
      for (int x = 0; x < m->conus_width(); x += 5) {
        MapPoint p;
        ASSERT_TRUE(m->undistort({float(x), float(y)}, &p));
        ASSERT_NEAR(rays[size_t(y) * m->conus_width() + x].u, p.u, kCoordTol);
        ASSERT_NEAR(rays[size_t(y) * m->conus_width() + x].v, p.v, kCoordTol);
      }
  }
  MapPoint out;
  EXPECT_FALSE(tensor.distort({640.0f, 10.0f}, &out));
  EXPECT_FALSE(tensor.undistort({-1.0f, 10.0f}, &out));
}

TEST(SamplingMap, RatesOneEverywhereIsTheIdentityCamera) {
  const SamplingMap m = SamplingMap::identity(64, 48, 8, 6);
  ASSERT_EQ(m.conus_width(), 64);
  ASSERT_EQ(m.conus_height(), 48);
  const std::vector<MapPoint> rays = m.rays();
  Image<float> img(64, 48);
  for (int y = 0; y < 48; ++y)
    for (int x = 0; x < 64; ++x) {
      img(x, y) = float(std::sin(0.3 * x) * std::cos(0.2 * y));
      EXPECT_NEAR(rays[size_t(y) * 64 + x].u, x, 1e-5f);
      EXPECT_NEAR(rays[size_t(y) * 64 + x].v, y, 1e-5f);
      MapPoint d;
      ASSERT_TRUE(m.distort({x + 0.25f, y - 0.25f}, &d));
      EXPECT_NEAR(d.u, x + 0.25f, 1e-5f);
      EXPECT_NEAR(d.v, y - 0.25f, 1e-5f);
    }
  const Image<float> conus = to_conus(img, m), back = from_conus(conus, m);
  for (size_t i = 0; i < img.size(); ++i) {
    EXPECT_NEAR(conus.pixels()[i], img.pixels()[i], 1e-5f);
    EXPECT_NEAR(back.pixels()[i], img.pixels()[i], 1e-5f);
  }
}

TEST(SamplingMap, StraightLinesStayConnected) {
  // The map is continuous and piecewise affine with local rates <= 1 here, so a straight line sampled every
  // 0.05 px maps to a polyline whose steps are at most 0.05 px (Lipschitz 1 per axis, sqrt(2) overall): no gap.
  // Within one triangle the image of the line is straight: three consecutive points stay collinear.
  const SamplingMap m = focus_context_map();
  const MapPoint a{10.0f, 400.0f}, b{630.0f, 30.0f};
  const float len = std::hypot(b.u - a.u, b.v - a.v), step = 0.05f;
  MapPoint prev;
  ASSERT_TRUE(m.distort(a, &prev));
  double max_step = 0.0;
  for (float s = step; s <= len; s += step) {
    const float t = s / len;
    MapPoint d;
    ASSERT_TRUE(m.distort({a.u + t * (b.u - a.u), a.v + t * (b.v - a.v)}, &d));
    max_step = std::max(max_step, std::hypot(double(d.u) - prev.u, double(d.v) - prev.v));
    prev = d;
  }
  EXPECT_LE(max_step, step * 1.0001 + 1e-4);
  EXPECT_GT(max_step, step * 0.4 * 0.5);  // it moved: not a degenerate map
}

TEST(SamplingMap, IncoherentOrBadMapsAreRefused) {
  EXPECT_THROW(SamplingMap::from_region_rates(64, 48, 4, 4, std::vector<float>(16, 0.0f)), Error);
  EXPECT_THROW(SamplingMap::from_region_rates(64, 48, 4, 4, std::vector<float>(15, 1.0f)), Error);
  EXPECT_THROW(SamplingMap::from_region_rates(0, 48, 4, 4, std::vector<float>(16, 1.0f)), Error);
  const SamplingMap m = SamplingMap::identity(64, 48, 4, 4);
  std::vector<MapPoint> nodes;
  for (int j = 0; j <= 4; ++j)
    for (int i = 0; i <= 4; ++i) nodes.push_back(m.node(i, j));
  std::vector<MapPoint> folded = nodes;
  folded[size_t(1) * 5 + 1].u = 40.0f;  // interior node pushed past its right neighbour (at 31.5)
  EXPECT_THROW(SamplingMap::from_nodes(64, 48, 64, 48, 4, 4, folded), Error);
  std::vector<MapPoint> off_border = nodes;
  off_border[2].v = 3.0f;  // a top border node moved inside
  EXPECT_THROW(SamplingMap::from_nodes(64, 48, 64, 48, 4, 4, off_border), Error);
}

}  // namespace
}  // namespace hf
