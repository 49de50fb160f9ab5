// registration/pixel_selection.h on analytic images, and the Gauss-Newton driver with a row selection.
#include "registration/pixel_selection.h"

#include <gtest/gtest.h>

#include <set>

#include "core/error.h"
#include "core/filters.h"
#include "reg_test_util.h"

namespace hf {
namespace {

// A fronto-parallel plane at z_m with every vertex valid, and an intensity image from f(x, y).
template <class F>
FramePyramidLevel analytic_level(int W, int H, float z_m, F intensity) {
  FramePyramidLevel l;
  l.camera = PinholeCamera{100.0, 100.0, W / 2.0, H / 2.0, W, H};
  l.vertices = VertexMap(W, H);
  l.normals = NormalMap(W, H, hf_make_float4(0, 0, -1, 1));
  l.intensity = IntensityImage(W, H);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      l.vertices(x, y) = hf_make_float4(float((x - W / 2.0) * z_m / 100.0), float((y - H / 2.0) * z_m / 100.0), z_m, 1);
      l.intensity(x, y) = intensity(x, y);
    }
  ImageGradients g = image_gradients(l.intensity);
  l.grad_x = std::move(g.dx);
  l.grad_y = std::move(g.dy);
  return l;
}

int count_in_tile(const Image<std::uint8_t>& m, int tx, int ty, int T) {
  int n = 0;
  for (int y = ty * T; y < std::min((ty + 1) * T, m.height()); ++y)
    for (int x = tx * T; x < std::min((tx + 1) * T, m.width()); ++x) n += m(x, y);
  return n;
}

PixelSelectionOptions options(PixelSelectionMode mode, int tile, int budget) {
  PixelSelectionOptions o;
  o.mode = mode;
  o.tile_px = tile;
  o.budget_per_tile = budget;
  return o;
}

TEST(DitherRank, IsAPermutationWhoseFirstQuarterIsTheEvenLattice) {
  for (int T : {2, 4, 16}) {
    std::set<int> ranks;
    for (int y = 0; y < T; ++y)
      for (int x = 0; x < T; ++x) {
        const int r = dither_rank(x, y, T);
        ranks.insert(r);
        EXPECT_EQ(r < T * T / 4, x % 2 == 0 && y % 2 == 0) << T << " " << x << "," << y;
      }
    EXPECT_EQ(int(ranks.size()), T * T);
    EXPECT_EQ(*ranks.rbegin(), T * T - 1);
  }
}

// Sobel / 8 of a unit step between columns 19 and 20 is 0.5 on both and 0 elsewhere: with a budget of two
// columns per tile, the tiles the edge crosses select exactly those two columns.
TEST(PixelSelection, StepEdgeSelectsTheEdgePixels) {
  const int W = 64, H = 32, T = 16;
  const FramePyramidLevel l = analytic_level(W, H, 1.0f, [](int x, int) { return x >= 20 ? 1.0f : 0.0f; });
  const Image<std::uint8_t> m = select_pixels(l, options(PixelSelectionMode::importance, T, 2 * T));
  for (int y = 0; y < H; ++y) {
    EXPECT_EQ(m(19, y), 1) << y;
    EXPECT_EQ(m(20, y), 1) << y;
    for (int x = 16; x < 32; ++x)
      if (x != 19 && x != 20) {
        EXPECT_EQ(m(x, y), 0) << x << "," << y;
      }
  }
  // A depth step (the same plane, the right half 10 % farther, flat intensity) selects the pixels beside it.
  FramePyramidLevel d = analytic_level(W, H, 1.0f, [](int, int) { return 0.5f; });
  for (int y = 0; y < H; ++y)
    for (int x = 40; x < W; ++x) d.vertices(x, y).z = 1.1f;
  const Image<std::uint8_t> md = select_pixels(d, options(PixelSelectionMode::importance, T, 2 * T));
  for (int y = 0; y < H; ++y) {
    EXPECT_EQ(md(39, y), 1) << y;
    EXPECT_EQ(md(40, y), 1) << y;
    EXPECT_EQ(md(38, y) + md(41, y), 0) << y;
  }
}

// Without any structure the importance is 0 everywhere and only the budget decides: exactly the uniform mask,
// which keeps the first `budget` dither ranks of each tile (a quarter: the even lattice).
TEST(PixelSelection, FlatImageSelectsByTheBudgetOnly) {
  const int W = 48, H = 40, T = 8, B = T * T / 4;
  const FramePyramidLevel l = analytic_level(W, H, 2.0f, [](int, int) { return 0.3f; });
  const Image<std::uint8_t> imp = select_pixels(l, options(PixelSelectionMode::importance, T, B));
  const Image<std::uint8_t> uni = select_pixels(l, options(PixelSelectionMode::uniform, T, B));
  EXPECT_EQ(imp.pixels(), uni.pixels());
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) EXPECT_EQ(uni(x, y), (x % 2 == 0 && y % 2 == 0) ? 1 : 0) << x << "," << y;
}

// With holes in the depth (no vertex), every tile keeps min(budget, valid pixels) and only valid ones, in both
// modes, also in partial tiles at the border; mode `all` keeps every valid pixel.
TEST(PixelSelection, BudgetRespectedPerTile) {
  const int W = 70, H = 45, T = 16, B = 40;  // partial tiles on the right and bottom
  FramePyramidLevel l = analytic_level(W, H, 1.5f, [](int x, int y) { return float((x * 7 + y * 13) % 17) / 17.0f; });
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x)
      if ((x * 31 + y * 17) % 5 == 0 || (x < 16 && y < 16 && (x + y) % 3 != 0)) l.vertices(x, y) = hf_invalid4();
  for (PixelSelectionMode mode : {PixelSelectionMode::importance, PixelSelectionMode::uniform}) {
    const Image<std::uint8_t> m = select_pixels(l, options(mode, T, B));
    for (int ty = 0; ty * T < H; ++ty)
      for (int tx = 0; tx * T < W; ++tx) {
        int valid = 0;
        for (int y = ty * T; y < std::min((ty + 1) * T, H); ++y)
          for (int x = tx * T; x < std::min((tx + 1) * T, W); ++x) {
            valid += l.vertices(x, y).w != 0.0f;
            if (m(x, y)) {
              EXPECT_NE(l.vertices(x, y).w, 0.0f);
            }
          }
        EXPECT_EQ(count_in_tile(m, tx, ty, T), std::min(B, valid)) << int(mode) << " tile " << tx << "," << ty;
      }
  }
  const Image<std::uint8_t> all = select_pixels(l, options(PixelSelectionMode::all, T, B));
  for (size_t i = 0; i < all.size(); ++i) EXPECT_EQ(all.pixels()[i], l.vertices.pixels()[i].w != 0.0f ? 1 : 0);

  VertexMap v = l.vertices;
  const Image<std::uint8_t> m = select_pixels(l, options(PixelSelectionMode::importance, T, B));
  apply_pixel_selection(m, &v);
  for (size_t i = 0; i < v.size(); ++i) EXPECT_EQ(v.pixels()[i].w != 0.0f, m.pixels()[i] == 1);
  EXPECT_THROW(apply_pixel_selection(Image<std::uint8_t>(3, 3), &v), Error);
  EXPECT_THROW(select_pixels(l, options(PixelSelectionMode::uniform, 12, 4)), Error);  // not a power of two
  EXPECT_THROW(select_pixels(l, options(PixelSelectionMode::uniform, 8, 65)), Error);  // over the tile
}

// The driver with a quarter of the finest level's pixels selected: every row comes from a selected pixel (rows
// <= selected pixels, inlier ratio against them), the options survive their keys, and combined still recovers a
// room pair's motion to the accuracy test's tolerance (1 cm, 1 deg: tests/registration/test_accuracy.cpp).
TEST(PixelSelection, DriverTracksOnTheSelectedRows) {
  const test::FramePair pair = test::make_pair("room", 0, 3, false);
  for (PixelSelectionMode mode : {PixelSelectionMode::importance, PixelSelectionMode::uniform}) {
    RegistrationOptions o = default_registration_options("combined");
    ASSERT_TRUE(o.set("row_selection", double(int(mode))));
    ASSERT_TRUE(o.set("row_selection_budget", 64));
    ASSERT_TRUE(o.set("finest_level_photometric_step", 1));
    test::MethodUnderTest m = test::method_under_test("combined", o, make_backend("cpu"));
    const RegistrationResult r = m.registration->align(pair.current, pair.reference, SE3());
    test::expect_finite(r);
    ASSERT_TRUE(r.usable()) << r.message;
    EXPECT_LT(test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true), 0.01) << int(mode);
    EXPECT_LT(test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true), 1.0) << int(mode);
    const Image<std::uint8_t> mask = select_pixels(pair.current.levels[0], o.driver.row_selection);
    long selected = 0;
    for (std::uint8_t b : mask.pixels()) selected += b;
    EXPECT_LE(r.inliers, 2 * selected);  // at most one icp and one photometric row per selected pixel
    EXPECT_GT(r.inlier_ratio, 0.3);      // against the selected pixels' rows, not all pixels'
    ASSERT_NE(m.dense, nullptr);
    EXPECT_EQ(m.dense->options().driver.row_selection.mode, mode);
  }
  RegistrationOptions bad = default_registration_options("icp");
  bad.driver.row_selection.budget_per_tile = 0;
  EXPECT_THROW(bad.validate(), Error);
}

}  // namespace
}  // namespace hf
