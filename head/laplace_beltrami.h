// The size-normalised cotangent Laplace-Beltrami operator (Kubásková section 3.1.3, eq. 8-9):
//   delta_i = (1 / d_i) sum_{(i,j) in E} w_ij (v_j - v_i),  w_ij = (cot alpha_ij + cot beta_ij) / 2,
//   d_i = S_i / 3, S_i the area of the triangles around v_i.
// (Eq. 8's "sum of weights = 1" describes normalised weights; the cotangent weights it then chooses do not sum to
// 1, and eq. 9 normalises by area instead.) The evaluation is |delta_i|, in 1 / mesh length: on a sphere of radius
// r it tends to 2/r (|delta| = 2 H with the barycentric area), on a plane it is 0.
// Defined at interior vertices with S_i > 0; elsewhere invalid and 0.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

struct LaplaceBeltrami {
  std::vector<Eigen::Vector3f> delta;  // the vector of eq. 9
  std::vector<float> magnitude;        // |delta|, the vertex evaluation
  std::vector<std::uint8_t> valid;
  int valid_count = 0;
};

LaplaceBeltrami laplace_beltrami(const TriangleMesh& mesh, const MeshTopology& topology);

}  // namespace hf::head
