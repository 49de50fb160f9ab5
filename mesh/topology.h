// Adjacency of an indexed triangle mesh (io/mesh.h): the undirected edges with the corners opposite them, each
// vertex's incident triangles and 1-ring, and what is not a closed 2-manifold (boundary edges, non-manifold
// edges, isolated vertices, degenerate triangles).
//
// Built once per mesh by build_topology() in O(V + F log F); immutable afterwards and safe to share between
// threads. Indices are those of the TriangleMesh; the topology does not own or copy positions, so the geometric
// helpers take the vertex array as an argument (units are the mesh's).
//
// Failure modes: build_topology() throws hf::Error when the mesh fails TriangleMesh::validate(). Everything
// unusual that is still a valid index set is recorded, never thrown: a triangle with a repeated index is listed
// in `degenerate_triangles` and left out of the adjacency; an edge with more than two triangles is
// non-manifold (its vertices are flagged, its first two triangles are kept as its sides).
#pragma once

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "io/mesh.h"

namespace hf {

// An undirected edge (v[0] < v[1]) and up to two triangles sharing it. opposite[s] is the corner of
// triangle[s] that is not on the edge (the vertex whose angle alpha / beta is "opposite the edge", Meyer et al.
// fig. 2a); -1 where the side is missing (a boundary edge has one side).
struct MeshEdge {
  std::array<int, 2> v{-1, -1};
  std::array<int, 2> triangle{-1, -1};
  std::array<int, 2> opposite{-1, -1};
  int triangle_count = 0;  // 1: boundary, 2: interior, > 2: non-manifold

  bool is_boundary() const { return triangle_count == 1; }
  bool is_manifold() const { return triangle_count <= 2; }
};

struct MeshTopology {
  int vertex_count = 0;
  std::vector<MeshEdge> edges;
  // CSR lists: the entries of vertex i are [offsets[i], offsets[i + 1]).
  std::vector<int> ring_offsets, ring;                  // 1-ring neighbours of each vertex, ascending
  std::vector<int> ring_edges;                          // edge index of (i, ring[k]), parallel to `ring`
  std::vector<int> triangle_offsets, vertex_triangles;  // incident (non-degenerate) triangles of each vertex
  std::vector<std::uint8_t> boundary_vertex;            // 1 where the vertex lies on a boundary edge
  std::vector<std::uint8_t> non_manifold_vertex;        // 1 where the vertex lies on a non-manifold edge
  std::vector<int> degenerate_triangles;                // triangles with a repeated index, left out
  int boundary_edge_count = 0, non_manifold_edge_count = 0, isolated_vertex_count = 0;

  int degree(int i) const { return ring_offsets[i + 1] - ring_offsets[i]; }
  const int* ring_begin(int i) const { return ring.data() + ring_offsets[i]; }
  const int* ring_end(int i) const { return ring.data() + ring_offsets[i + 1]; }
  bool is_isolated(int i) const { return degree(i) == 0; }
  // A vertex whose neighbourhood is a closed disc: not on a boundary or non-manifold edge, not isolated.
  bool is_interior(int i) const { return !boundary_vertex[i] && !non_manifold_vertex[i] && degree(i) > 0; }
  bool closed_manifold() const { return boundary_edge_count == 0 && non_manifold_edge_count == 0; }
};

MeshTopology build_topology(const TriangleMesh& mesh);

// The cotangent of the angle at corner `apex` of the triangle (apex, a, b), in double. Returns 0 for a degenerate
// (zero-area or zero-length) triangle, where the angle is undefined, so cotangent sums stay finite; callers that
// must know test triangle_area() first.
double corner_cotangent(const std::vector<Eigen::Vector3f>& positions, int apex, int a, int b);
// The angle (radians) at corner `apex` of (apex, a, b); 0 when an adjacent side has zero length.
double corner_angle(const std::vector<Eigen::Vector3f>& positions, int apex, int a, int b);
double triangle_area(const std::vector<Eigen::Vector3f>& positions, const Eigen::Vector3i& t);
// cot(alpha) + cot(beta) of an edge's two opposite corners; a boundary edge contributes its one side.
double edge_cotangent_weight(const std::vector<Eigen::Vector3f>& positions, const MeshEdge& e);
// The cotangent Laplacian's sum at every vertex, sum_j (cot alpha_ij + cot beta_ij) (v_j - v_i), in double: the
// mean-curvature normal of Meyer et al. is -1/(2 A) of it, the Laplace-Beltrami operator of Nealen et al. half of
// it over an area.
std::vector<Eigen::Vector3d> cotangent_laplacian_sums(const std::vector<Eigen::Vector3f>& positions,
                                                      const MeshTopology& topology);

}  // namespace hf
