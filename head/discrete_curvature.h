// Discrete mean and Gaussian curvature of Meyer, Desbrun, Schröder and Barr ("Discrete differential-geometry
// operators for triangulated 2-manifolds"), Kubásková section 3.1.1:
//   A_mixed  Voronoi area of each non-obtuse triangle's corner, 1/2 of the triangle's area at an obtuse corner,
//            1/4 at the other corners of an obtuse triangle;
//   H (eq. 3) = |sum_j (cot alpha_ij + cot beta_ij) (v_i - v_j)| / (4 A_mixed), Meyer's mean-curvature normal
//            (the paper prints ||v_i - v_j||^2 inside the sum, which is 8 A_Voronoi and not a curvature; Meyer's
//            vector form is what its citation [10] defines). Unsigned, as the paper notes;
//   K (eq. 4) = (2 pi - sum of corner angles) / A_mixed;   k_max/min from eq. 5 with the H^2 < K guard.
// Defined at interior vertices only (closed 1-ring, manifold edges, positive A_mixed); every other vertex is
// invalid and 0 (curvature.h). Dihedral accuracy: on a uniformly refined sphere H and K converge to 1/r and
// 1/r^2 (tests/head/test_discrete_curvature.cpp states the measured order).
#pragma once

#include <vector>

#include "head/curvature.h"
#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

// A_mixed per vertex (0 at isolated vertices), in squared mesh units.
std::vector<double> mixed_areas(const TriangleMesh& mesh, const MeshTopology& topology);

VertexCurvatures discrete_curvature(const TriangleMesh& mesh, const MeshTopology& topology);

}  // namespace hf::head
