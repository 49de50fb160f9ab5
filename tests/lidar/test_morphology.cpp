// Operator laws of Cvirn section 3 on random binary rasters: the variant dilation is exactly the union of its
// discs, extensive and increasing; area openings are anti-extensive, increasing and idempotent; the
// second-generation opening is a subset of S; the differential profile partitions S and equals the paper's set
// differences of nested openings.
#include <gtest/gtest.h>

#include <random>

#include "core/error.h"
#include "lidar/attribute_opening.h"
#include "lidar/connected_components.h"
#include "lidar/differential_profile.h"
#include "lidar/validation.h"
#include "lidar/variant_dilation.h"

namespace hf::lidar {
namespace {

Mask random_mask(int w, int h, double density, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::bernoulli_distribution on(density);
  Mask m(w, h, 0);
  for (auto& v : m.pixels()) v = on(rng) ? 1 : 0;
  return m;
}

// Random blocks ("buildings") of varied size.
Mask random_blocks(int w, int h, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> px(0, w - 1), py(0, h - 1), size(1, 6);
  Mask m(w, h, 0);
  for (int i = 0; i < n; ++i) {
    const int x0 = px(rng), y0 = py(rng), sx = size(rng), sy = size(rng);
    for (int y = y0; y < std::min(h, y0 + sy); ++y)
      for (int x = x0; x < std::min(w, x0 + sx); ++x) m(x, y) = 1;
  }
  return m;
}

Image<float> random_radii(const Mask& m, std::uint64_t seed, float max_r) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<float> r(0.0f, max_r);
  Image<float> out(m.width(), m.height(), 0.0f);
  for (auto& v : out.pixels()) v = r(rng);
  return out;
}

Mask union_of(const Mask& a, const Mask& b) {
  Mask u = a;
  for (size_t i = 0; i < u.size(); ++i) u.pixels()[i] |= b.pixels()[i];
  return u;
}

bool subset(const Mask& a, const Mask& b) {
  for (size_t i = 0; i < a.size(); ++i)
    if (a.pixels()[i] && !b.pixels()[i]) return false;
  return true;
}

Mask brute_dilation(const Mask& m, const Image<float>& radius) {
  Mask out(m.width(), m.height(), 0);
  for (int sy = 0; sy < m.height(); ++sy)
    for (int sx = 0; sx < m.width(); ++sx) {
      if (!m(sx, sy)) continue;
      const double r = std::max(0.0f, radius(sx, sy));
      for (int y = 0; y < m.height(); ++y)
        for (int x = 0; x < m.width(); ++x)
          if (double(x - sx) * (x - sx) + double(y - sy) * (y - sy) <= r * r) out(x, y) = 1;
    }
  return out;
}

TEST(VariantDilation, EqualsTheUnionOfDiscs) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Mask s = seed % 2 ? random_blocks(48, 40, 12, seed) : random_mask(48, 40, 0.08, seed);
    // Per-component radii (as psi uses) and fully random per-cell radii (the general operator).
    const Components c = connected_components(s);
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<float> rr(0.0f, 7.5f);
    std::vector<float> per(static_cast<size_t>(c.count));
    for (auto& v : per) v = rr(rng);
    Image<float> comp_r(s.width(), s.height(), 0.0f);
    for (size_t i = 0; i < s.size(); ++i)
      if (c.label.pixels()[i] >= 0) comp_r.pixels()[i] = per[c.label.pixels()[i]];
    EXPECT_EQ(variant_dilation(s, comp_r).pixels(), brute_dilation(s, comp_r).pixels()) << "seed " << seed;
    const Image<float> cell_r = random_radii(s, seed + 100, 6.0f);
    EXPECT_EQ(variant_dilation(s, cell_r).pixels(), brute_dilation(s, cell_r).pixels()) << "seed " << seed;
  }
}

TEST(VariantDilation, ExtensiveAndIncreasing) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Mask small = random_blocks(64, 64, 10, seed);
    const Mask big = union_of(small, random_blocks(64, 64, 6, seed + 50));
    const Image<float> r = random_radii(big, seed, 5.0f);
    const Mask ds = variant_dilation(small, r), db = variant_dilation(big, r);
    EXPECT_TRUE(subset(small, ds));
    EXPECT_TRUE(subset(ds, db));
  }
  // Radius 0 (or negative) is the identity.
  const Mask s = random_mask(20, 20, 0.3, 9);
  EXPECT_EQ(variant_dilation(s, Image<float>(20, 20, -1.0f)).pixels(), s.pixels());
}

TEST(AreaOpening, AntiExtensiveIncreasingIdempotent) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Mask x = random_mask(60, 50, 0.45, seed);
    const Mask y = union_of(x, random_mask(60, 50, 0.1, seed + 9));
    for (double a : {1.0, 4.0, 20.0, 300.0}) {
      const Mask ox = area_opening(x, a, 1.0);
      EXPECT_TRUE(subset(ox, x));
      EXPECT_EQ(area_opening(ox, a, 1.0).pixels(), ox.pixels());
      EXPECT_TRUE(subset(ox, area_opening(y, a, 1.0)));
      // Every kept component has area >= a; every removed one < a.
      const Components c = connected_components(x);
      for (size_t i = 0; i < x.size(); ++i)
        if (const int id = c.label.pixels()[i]; id >= 0) {
          EXPECT_EQ(ox.pixels()[i] != 0, c.cells[id] >= a);
        }
    }
  }
}

TEST(AreaOpening, AreaIsInSquareMetres) {
  Mask m(10, 10, 0);
  for (int y = 0; y < 2; ++y)
    for (int x = 0; x < 2; ++x) m(x, y) = 1;  // 4 cells of 0.5 m: 1 m^2
  EXPECT_EQ(area_opening(m, 1.0, 0.5).pixels(), m.pixels());
  EXPECT_EQ(area_opening(m, 1.01, 0.5).pixels(), Mask(10, 10, 0).pixels());
}

TEST(SecondGenerationOpening, SubsetOfSAndJoinsClusters) {
  // Two 2x2 blocks 3 cells apart: alone each has 4 cells, clustered by a radius-2 dilation they form one cluster.
  Mask s(12, 6, 0);
  for (int y = 2; y < 4; ++y) s(2, y) = s(3, y) = s(7, y) = s(8, y) = 1;
  const Mask psi = variant_dilation(s, Image<float>(12, 6, 2.0f));
  const Mask g = second_generation_opening(s, psi, 20.0, 1.0);
  EXPECT_TRUE(subset(g, s));
  EXPECT_EQ(g.pixels(), s.pixels());  // the cluster's area (> 20 cells) keeps both blocks
  EXPECT_EQ(area_opening(s, 20.0, 1.0).pixels(), Mask(12, 6, 0).pixels());  // first generation removes both
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    const Mask rs = random_blocks(50, 50, 15, seed);
    const Mask rpsi = variant_dilation(rs, random_radii(rs, seed, 4.0f));
    for (double a : {10.0, 100.0, 600.0}) EXPECT_TRUE(subset(second_generation_opening(rs, rpsi, a, 1.0), rs));
  }
}

TEST(DifferentialProfile, PartitionsSAndEqualsTheSetDifferences) {
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    const Mask s = random_blocks(80, 70, 25, seed);
    const Mask psi = variant_dilation(s, random_radii(s, seed, 4.0f));
    const AreaThresholds a{40, 200, 900};
    const Profile p = differential_profile(s, psi, a, 1.0);
    const Mask g1 = second_generation_opening(s, psi, a.a1, 1.0), g2 = second_generation_opening(s, psi, a.a2, 1.0),
               g3 = second_generation_opening(s, psi, a.a3, 1.0);
    std::int64_t cells = 0;
    for (size_t i = 0; i < s.size(); ++i) {
      const bool in_s = s.pixels()[i], in1 = g1.pixels()[i], in2 = g2.pixels()[i], in3 = g3.pixels()[i];
      // The paper's rules: S^H = S \ G1, S^V = G1 \ G2, S^T = G2 \ G3, S^C = G3.
      const int expected = !in_s ? 0 : !in1 ? 1 : !in2 ? 2 : !in3 ? 3 : 4;
      EXPECT_EQ(p.classes.pixels()[i], expected);
      cells += in_s;
    }
    std::int64_t sum = 0, buildings = 0;
    for (const auto& st : p.stats) sum += st.cells, buildings += st.components;
    EXPECT_EQ(sum, cells);  // a partition: every cell of S in exactly one class
    EXPECT_EQ(buildings, connected_components(s).count);  // each building lies in one cluster
  }
  EXPECT_THROW(validate(AreaThresholds{10, 5, 20}), hf::Error);
}

TEST(Validation, ScoresFollowEquationsSevenToNine) {
  const Scores s = scores_from_counts(30, 10, 20);
  EXPECT_DOUBLE_EQ(s.completeness, 30.0 / 50.0);
  EXPECT_DOUBLE_EQ(s.correctness, 30.0 / 40.0);
  EXPECT_DOUBLE_EQ(s.f1, 2 * 0.6 * 0.75 / 1.35);
  const Scores none = scores_from_counts(0, 0, 0);
  EXPECT_FALSE(none.contained);
  EXPECT_EQ(none.f1, 0.0);
  Image<std::uint8_t> truth(4, 1, 0), result(4, 1, 0);
  truth(0, 0) = 1, truth(1, 0) = 1, truth(2, 0) = 2;
  result(0, 0) = 1, result(1, 0) = 2, result(2, 0) = 2, result(3, 0) = 2;
  const ClassValidation v = compare_classes(result, truth);
  EXPECT_EQ(v.per_class[0].tp, 1);
  EXPECT_EQ(v.per_class[0].fn, 1);
  EXPECT_EQ(v.per_class[1].tp, 1);
  EXPECT_EQ(v.per_class[1].fp, 2);
  EXPECT_FALSE(v.per_class[2].contained);
  EXPECT_DOUBLE_EQ(v.mean_f1, (v.per_class[0].f1 + v.per_class[1].f1) / 2);
}

}  // namespace
}  // namespace hf::lidar
