// io/associate: TUM associate.py semantics (candidates under the max difference, greedy by difference,
// one-to-one, sorted by the first list), checked on hand cases and against a literal port of the script.
#include "io/associate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

namespace {

using Pairs = std::vector<std::pair<size_t, size_t>>;

Pairs pairs(const std::vector<hf::Match>& matches) {
  Pairs p;
  for (const hf::Match& m : matches) p.emplace_back(m.a, m.b);
  return p;
}

// associate.py, line for line: all pairs, sort by difference, take greedily, sort the result.
Pairs reference(const std::vector<double>& a, const std::vector<double>& b, double offset, double max_difference) {
  std::vector<std::tuple<double, size_t, size_t>> potential;
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j)
      if (std::fabs(a[i] - (b[j] + offset)) < max_difference) potential.emplace_back(std::fabs(a[i] - (b[j] + offset)), i, j);
  std::sort(potential.begin(), potential.end());
  std::set<size_t> left_a, left_b;
  for (size_t i = 0; i < a.size(); ++i) left_a.insert(i);
  for (size_t j = 0; j < b.size(); ++j) left_b.insert(j);
  Pairs matches;
  for (const auto& [diff, i, j] : potential) {
    if (left_a.count(i) && left_b.count(j)) {
      left_a.erase(i);
      left_b.erase(j);
      matches.emplace_back(i, j);
    }
  }
  std::sort(matches.begin(), matches.end());
  return matches;
}

}  // namespace

TEST(Associate, JitterWithinToleranceMatchesOneToOne) {
  const std::vector<double> rgb = {0.0, 0.033, 0.066, 0.1};
  const std::vector<double> depth = {0.004, 0.027, 0.079, 0.2};
  EXPECT_EQ(pairs(hf::associate(rgb, depth)), (Pairs{{0, 0}, {1, 1}, {2, 2}}));
}

TEST(Associate, DifferenceMustBeStrictlyBelowTheMaximum) {
  // |0.02 - 0| == 0.02 exactly in double: not a candidate, as in the script's '<'.
  EXPECT_TRUE(hf::associate({0.0}, {0.02}).empty());
  EXPECT_EQ(hf::associate({0.0}, {0.0199}).size(), 1u);
  hf::AssociationOptions wide;
  wide.max_difference_s = 0.05;
  EXPECT_EQ(hf::associate({0.0}, {0.04}, wide).size(), 1u);
}

TEST(Associate, GreedyByDifferenceNotNearestNeighbour) {
  // Both a0 and a1 are closest to b0; the smaller difference (a1) wins it, a0 stays unmatched although b1 is
  // free (it is 0.025 away, beyond the maximum).
  EXPECT_EQ(pairs(hf::associate({0.0, 0.015}, {0.01, 0.025})), (Pairs{{1, 0}}));
  // Greedy is not a maximum matching: a0-b1 (0.004) is taken first, which leaves a1 and b0 without partners
  // although a0-b0 (0.015) and a1-b1 (0.012) would have matched both. associate.py does the same.
  EXPECT_EQ(pairs(hf::associate({0.0, 0.016}, {-0.015, 0.004})), (Pairs{{0, 1}}));
}

TEST(Associate, OffsetIsAddedToTheSecondList) {
  const std::vector<double> rgb = {10.0, 10.033, 10.066};
  const std::vector<double> depth = {9.501, 9.534, 9.565};
  EXPECT_TRUE(hf::associate(rgb, depth).empty());
  hf::AssociationOptions o;
  o.offset_s = 0.5;
  EXPECT_EQ(pairs(hf::associate(rgb, depth, o)), (Pairs{{0, 0}, {1, 1}, {2, 2}}));
  o.offset_s = -0.5;
  EXPECT_TRUE(hf::associate(rgb, depth, o).empty());
}

TEST(Associate, EmptyInputsAndResultSortedByFirstList) {
  EXPECT_TRUE(hf::associate({}, {}).empty());
  EXPECT_TRUE(hf::associate({1.0}, {}).empty());
  EXPECT_TRUE(hf::associate({}, {1.0}).empty());
  const auto m = hf::associate({0.0, 0.01, 0.02, 0.03}, {0.001, 0.011, 0.021, 0.031});
  ASSERT_EQ(m.size(), 4u);
  for (size_t i = 1; i < m.size(); ++i) EXPECT_LT(m[i - 1].a, m[i].a);
}

TEST(Associate, AgreesWithTheScriptOnRandomStreams) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.015, 0.015), drop(0.0, 1.0), period(0.02, 0.04);
  for (int trial = 0; trial < 200; ++trial) {
    std::vector<double> a, b;
    double ta = 1305031229.0, tb = ta;
    const double dt_a = period(rng), dt_b = period(rng);
    for (int k = 0; k < 60; ++k) {
      ta += dt_a + 0.1 * jitter(rng);
      tb += dt_b + 0.1 * jitter(rng);
      if (drop(rng) > 0.1) a.push_back(ta);
      if (drop(rng) > 0.1) b.push_back(tb + jitter(rng) * 0.01);
    }
    std::sort(b.begin(), b.end());
    hf::AssociationOptions o;
    o.offset_s = trial % 3 == 0 ? 0.0 : jitter(rng);
    o.max_difference_s = trial % 2 == 0 ? 0.02 : 0.01;
    ASSERT_EQ(pairs(hf::associate(a, b, o)), reference(a, b, o.offset_s, o.max_difference_s)) << "trial " << trial;
  }
}
