// Curvature from the modified MLS approximation of Kim and Kim (Kubásková section 3.1.2):
//   1. the reference plane H at v_i is orthogonal to the mean of the unit normals of the triangles around v_i;
//   2. the k-neighbourhood N_i^k (mesh/k_ring.h) is projected onto H in an orthonormal frame centred at v_i, with
//      heights f_j = n^T (v_j - v_i);
//   3. a cubic p(x) = b(x)^T c is fitted by weighted least squares, theta = exp(-|v_i - v_j|^2 / h^2), h = the
//      mean length of v_i's 1-ring edges (eq. 6; the paper's factor 2 on A but not on d is dropped, it would halve
//      c). Coordinates are divided by h before the fit so the 10 x 10 system is well scaled at any mesh unit;
//   4. the principal curvatures and directions are those of the implicit surface F = z - p(x, y) at the origin
//      (kappa = F_ij t_i t_j / |grad F|, directions the eigenvectors of grad n, eq. 7), computed as the eigen-
//      system of the graph's shape operator I^-1 II.
// Signed: positive where the surface bends away from the normal (a sphere with outward normals: +1/r), so concave
// regions (eye sockets) are negative. The normals are taken outward: when the triangles' winding makes them point
// inward on the whole (negative signed volume about the centroid), every normal is flipped.
// Invalid vertices (curvature.h): not interior, fewer than 6 neighbours in N_i^k (a quadratic is fitted when there
// are 6 to 9, the cubic needs 10), or a rank-deficient fit.
#pragma once

#include <cstdint>
#include <vector>

#include "head/curvature.h"
#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

struct MlsOptions {
  int k = 3;  // neighbourhood rings: the paper's usual choice (1 and 2 rings give a poor surface, section 3.1.2)
  // > 0: the fit at a physical scale (mesh units) instead of the mesh's: h = this instead of the mean 1-ring edge,
  // and N^k grown until it reaches 2 h (k >= 2 h / (0.75 x the vertex's mean 1-ring edge)), so two meshes of one
  // surface at different vertex densities fit over the same extent. 0: the paper's rule above.
  double h = 0.0;
};

// Evaluates every vertex, or only those with only[i] != 0 when `only` is non-empty (the automatic detection needs
// MLS on the eye and ear areas only). Vertices skipped that way are invalid.
VertexCurvatures mls_curvature(const TriangleMesh& mesh, const MeshTopology& topology, const MlsOptions& options = {},
                               const std::vector<std::uint8_t>& only = {});

// Unit vertex normals as step 1 defines them (mean of incident unit face normals), oriented outward as above;
// (0, 0, 0) at vertices without a non-degenerate triangle.
std::vector<Eigen::Vector3f> mls_vertex_normals(const TriangleMesh& mesh, const MeshTopology& topology);

}  // namespace hf::head
