// Morphology on mesh vertex sets: the definitions (against brute-force k-rings) and the identities erode <= set <=
// dilate, idempotent opening and closing, duality with the complement.
#include <gtest/gtest.h>

#include <random>

#include "head/morphology.h"
#include "mesh/k_ring.h"
#include "tests/common/analytic_meshes.h"

namespace hf::head {
namespace {

VertexMask random_set(int n, double p, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution b(p);
  VertexMask s(n);
  for (auto& v : s) v = b(rng);
  return s;
}

bool subset(const VertexMask& a, const VertexMask& b) {
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i] && !b[i]) return false;
  return true;
}

VertexMask complement(VertexMask s) {
  for (auto& v : s) v = !v;
  return s;
}

class MorphologyOnMeshes : public ::testing::TestWithParam<int> {};

TEST_P(MorphologyOnMeshes, DefinitionsAndIdentities) {
  // 0: closed sphere; 1: open grid (erosion near the border sees the smaller N^k).
  const TriangleMesh m = GetParam() == 0 ? test::icosphere(1.0, 3)
                                         : test::height_field(25, 1.0, [](double, double) { return 0.0; });
  const MeshTopology t = build_topology(m);
  KRing walker(t);
  std::vector<int> ring;
  for (unsigned seed : {1u, 2u}) {
    const VertexMask s = random_set(t.vertex_count, 0.6, seed);
    for (int k : {1, 2, 3}) {
      const VertexMask d = dilate(t, s, k), e = erode(t, s, k);
      // The definitions, vertex by vertex.
      for (int j = 0; j < t.vertex_count; ++j) {
        walker.collect(j, k, ring);
        bool any = false, all = true;
        for (int i : ring) {
          any = any || s[i];
          all = all && s[i];
        }
        ASSERT_EQ(d[j] != 0, any) << "dilate, vertex " << j;
        ASSERT_EQ(e[j] != 0, all) << "erode, vertex " << j;
      }
      EXPECT_TRUE(subset(e, s));
      EXPECT_TRUE(subset(s, d));
      const VertexMask o = open(t, s, k), c = close(t, s, k);
      EXPECT_TRUE(subset(o, s));
      EXPECT_TRUE(subset(s, c));
      EXPECT_EQ(open(t, o, k), o) << "opening is idempotent";
      EXPECT_EQ(close(t, c, k), c) << "closing is idempotent";
      EXPECT_EQ(erode(t, s, k), complement(dilate(t, complement(s), k)));
      EXPECT_EQ(open(t, s, k), complement(close(t, complement(s), k)));
      EXPECT_EQ(dilate(t, d, k), dilate(t, s, 2 * k)) << "dilate^k twice is dilate^2k";
    }
  }
  const VertexMask s = random_set(t.vertex_count, 0.5, 9);
  EXPECT_EQ(apply_morphology(t, s, {{MorphologyOp::open, 2}, {MorphologyOp::dilate, 1}}), dilate(t, open(t, s, 2), 1));
  EXPECT_EQ(dilate(t, s, 0), s);
}

INSTANTIATE_TEST_SUITE_P(Meshes, MorphologyOnMeshes, ::testing::Values(0, 1));

}  // namespace
}  // namespace hf::head
