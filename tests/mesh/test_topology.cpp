// Mesh adjacency: edges with their opposite corners, 1-rings, k-rings (against a brute-force distance), boundary,
// non-manifold, isolated and degenerate elements.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>

#include "mesh/k_ring.h"
#include "mesh/topology.h"
#include "tests/common/analytic_meshes.h"

namespace hf {
namespace {

TEST(MeshTopology, ClosedIcosphereIsAManifoldWithEulerCharacteristicTwo) {
  const TriangleMesh m = test::icosphere(1.0, 2);
  const MeshTopology t = build_topology(m);
  EXPECT_TRUE(t.closed_manifold());
  EXPECT_EQ(t.isolated_vertex_count, 0);
  // V - E + F = 2 for a sphere; every edge has two sides with distinct opposite corners.
  EXPECT_EQ(static_cast<long>(m.vertices.size()) - static_cast<long>(t.edges.size()) +
                static_cast<long>(m.triangles.size()),
            2);
  for (const MeshEdge& e : t.edges) {
    ASSERT_EQ(e.triangle_count, 2);
    EXPECT_LT(e.v[0], e.v[1]);
    EXPECT_NE(e.opposite[0], e.opposite[1]);
    for (int s = 0; s < 2; ++s) {
      const Eigen::Vector3i& tri = m.triangles[e.triangle[s]];
      int hits = 0;
      for (int k = 0; k < 3; ++k) hits += tri[k] == e.v[0] || tri[k] == e.v[1];
      EXPECT_EQ(hits, 2);
      EXPECT_TRUE(tri[0] == e.opposite[s] || tri[1] == e.opposite[s] || tri[2] == e.opposite[s]);
    }
  }
  // The 12 original icosahedron vertices keep degree 5, all others have 6.
  int five = 0;
  for (int i = 0; i < t.vertex_count; ++i) {
    EXPECT_TRUE(t.degree(i) == 5 || t.degree(i) == 6);
    five += t.degree(i) == 5;
    EXPECT_TRUE(std::is_sorted(t.ring_begin(i), t.ring_end(i)));
    EXPECT_EQ(t.triangle_offsets[i + 1] - t.triangle_offsets[i], t.degree(i));
  }
  EXPECT_EQ(five, 12);
}

TEST(MeshTopology, GridBoundaryIsItsBorder) {
  const int n = 7;
  const TriangleMesh m = test::height_field(n, 1.0, [](double, double) { return 0.0; });
  const MeshTopology t = build_topology(m);
  EXPECT_EQ(t.boundary_edge_count, 4 * (n - 1));
  EXPECT_EQ(t.non_manifold_edge_count, 0);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool border = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      EXPECT_EQ(t.boundary_vertex[j * n + i] != 0, border) << i << "," << j;
      EXPECT_EQ(t.is_interior(j * n + i), !border);
    }
}

TEST(MeshTopology, OppositeAnglesOfTwoRightTriangles) {
  // The unit square split along (0, 2): both corners opposite that diagonal are right angles (cot = 0), and the
  // corners opposite a side are 45 degrees (cot = 1).
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  const MeshTopology t = build_topology(m);
  ASSERT_EQ(t.edges.size(), 5u);
  for (const MeshEdge& e : t.edges) {
    if (e.v[0] == 0 && e.v[1] == 2) {
      EXPECT_EQ(e.triangle_count, 2);
      EXPECT_NEAR(edge_cotangent_weight(m.vertices, e), 0.0, 1e-12);
      EXPECT_NEAR(corner_angle(m.vertices, e.opposite[0], 0, 2), std::numbers::pi / 2, 1e-12);
    } else {
      EXPECT_TRUE(e.is_boundary());
      EXPECT_NEAR(edge_cotangent_weight(m.vertices, e), 1.0, 1e-6);
    }
  }
}

TEST(MeshTopology, RecordsNonManifoldIsolatedAndDegenerate) {
  TriangleMesh m;
  // Three triangles on edge (0, 1): non-manifold. Vertex 5 is used by nothing; triangle (0, 0, 2) is degenerate.
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {5, 5, 5}};
  m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {0, 0, 2}};
  const MeshTopology t = build_topology(m);
  EXPECT_EQ(t.non_manifold_edge_count, 1);
  EXPECT_TRUE(t.non_manifold_vertex[0] && t.non_manifold_vertex[1]);
  EXPECT_EQ(t.isolated_vertex_count, 1);
  EXPECT_TRUE(t.is_isolated(5));
  ASSERT_EQ(t.degenerate_triangles.size(), 1u);
  EXPECT_EQ(t.degenerate_triangles[0], 3);
  EXPECT_FALSE(t.is_interior(0));
}

TEST(MeshTopology, RejectsIndicesOutsideTheVertices) {
  TriangleMesh m;
  m.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 3}};
  EXPECT_THROW(build_topology(m), Error);
}

// Brute-force graph distances from `source` by repeated relaxation, the definition N^k is held to.
std::vector<int> brute_distance(const MeshTopology& t, int source) {
  std::vector<int> d(t.vertex_count, 1 << 20);
  d[source] = 0;
  for (bool changed = true; changed;) {
    changed = false;
    for (const MeshEdge& e : t.edges)
      for (int s = 0; s < 2; ++s)
        if (d[e.v[s]] + 1 < d[e.v[1 - s]]) {
          d[e.v[1 - s]] = d[e.v[s]] + 1;
          changed = true;
        }
  }
  return d;
}

TEST(KRing, MatchesBruteForceDistanceAndIsReusable) {
  const TriangleMesh m = test::icosphere(1.0, 2);
  const MeshTopology t = build_topology(m);
  KRing walker(t);
  std::vector<int> out;
  for (int source : {0, 17, 100}) {
    const std::vector<int> d = brute_distance(t, source);
    for (int k = 0; k <= 4; ++k) {
      walker.collect(source, k, out);
      EXPECT_EQ(out.front(), source);
      std::set<int> got(out.begin(), out.end());
      EXPECT_EQ(got.size(), out.size()) << "duplicates";
      std::set<int> want;
      for (int i = 0; i < t.vertex_count; ++i)
        if (d[i] <= k) want.insert(i);
      EXPECT_EQ(got, want) << "source " << source << " k " << k;
    }
  }
  // Multi-source distance is the minimum over the sources.
  std::vector<std::uint8_t> set(t.vertex_count, 0);
  set[0] = set[100] = 1;
  const std::vector<int> multi = multi_source_distance(t, set, 3);
  const std::vector<int> d0 = brute_distance(t, 0), d1 = brute_distance(t, 100);
  for (int i = 0; i < t.vertex_count; ++i) EXPECT_EQ(multi[i], std::min(std::min(d0[i], d1[i]), 4));
}

}  // namespace
}  // namespace hf
