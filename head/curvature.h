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

}  // namespace hf::head
