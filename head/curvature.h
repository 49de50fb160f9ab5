// Per-vertex curvature of a triangle mesh, the common result of the two curvature evaluations of Kubásková's
// section 3.1 (discrete_curvature.h: Meyer et al.'s operators; mls_curvature.h: the modified MLS fit).
//
// Units: curvatures are 1 / (the mesh's length unit), Gaussian curvature 1 / length^2. A sphere of radius r with
// outward normals has mean = k_max = k_min = 1/r and gaussian = 1/r^2. Vertices where the operator is undefined
// (boundary, non-manifold or isolated vertices, zero area, a fit without enough support) have valid = 0 and every
// value 0, so no NaN or inf ever leaves an evaluation.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "io/mesh.h"
#include "mesh/topology.h"

namespace hf::head {

struct VertexCurvatures {
  std::vector<float> mean;      // H = (k_max + k_min) / 2 (eq. 2)
  std::vector<float> gaussian;  // K = k_max * k_min (eq. 1)
  std::vector<float> k_max, k_min;
  std::vector<Eigen::Vector3f> dir_max, dir_min;  // unit principal directions; MLS only (empty for discrete)
  std::vector<std::uint8_t> valid;
  int valid_count = 0;

  void resize(int n, bool with_directions);
  size_t size() const { return mean.size(); }
};

// Eq. 5: k_max/min = H +- sqrt(H^2 - K), with the square root taken as 0 where H^2 < K (the paper's guard against
// the discrete H and K disagreeing).
void principal_from_mean_gaussian(double H, double K, double* k_max, double* k_min);

// An evaluation at a physical scale: each valid vertex's value replaced by the mean over the valid vertices within
// 2.5 sigma (mesh units, Euclidean, reached through the mesh: N^k with k = ceil(2.5 sigma / (0.75 mean edge))),
// weighted by exp(-d^2 / (2 sigma^2)) times the vertex's barycentric area (a third of its triangles'), so the
// result is an integral over a disc of the surface and does not depend on the vertex density. A value at the
// scale of the mesh's own noise (a fused head's voxel-scale ripple) averages out over a sigma of a few voxels,
// where a 1-ring evaluation would measure it. sigma <= 0 leaves the values as they are. Invalid vertices keep 0.
void smooth_at_scale(const TriangleMesh& mesh, const MeshTopology& topology, double sigma,
                     const std::vector<std::uint8_t>& valid, std::vector<std::vector<float>*> fields);
// Every scalar field of c (mean, gaussian, k_max, k_min; not the directions).
void smooth_at_scale(const TriangleMesh& mesh, const MeshTopology& topology, double sigma, VertexCurvatures& c);

}  // namespace hf::head
