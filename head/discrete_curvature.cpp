#include "head/discrete_curvature.h"

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

namespace hf::head {

std::vector<double> mixed_areas(const TriangleMesh& mesh, const MeshTopology& topology) {
  const std::vector<Eigen::Vector3f>& p = mesh.vertices;
  std::vector<double> area(topology.vertex_count, 0.0);
  std::vector<std::uint8_t> degenerate(mesh.triangles.size(), 0);
  for (int t : topology.degenerate_triangles) degenerate[t] = 1;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (degenerate[t]) continue;
    const Eigen::Vector3i& tri = mesh.triangles[t];
    const double a = triangle_area(p, tri);
    if (!(a > 0.0)) continue;
    double cot[3], len2[3];  // cot of the angle at corner k; squared length of the side opposite corner k
    int obtuse = -1;
    for (int k = 0; k < 3; ++k) {
      const int i = tri[k], j = tri[(k + 1) % 3], l = tri[(k + 2) % 3];
      cot[k] = corner_cotangent(p, i, j, l);
      len2[k] = (p[j] - p[l]).cast<double>().squaredNorm();
      if (cot[k] < 0.0) obtuse = k;
    }
    for (int k = 0; k < 3; ++k) {
      double share;
      if (obtuse < 0) {
        // Voronoi region of corner k: the two sides at k, each weighted by the cotangent of the angle opposite it.
        share = (len2[(k + 1) % 3] * cot[(k + 1) % 3] + len2[(k + 2) % 3] * cot[(k + 2) % 3]) / 8.0;
      } else {
        share = obtuse == k ? a / 2.0 : a / 4.0;
      }
      area[tri[k]] += share;
    }
  }
  return area;
}

VertexCurvatures discrete_curvature(const TriangleMesh& mesh, const MeshTopology& topology) {
  const std::vector<Eigen::Vector3f>& p = mesh.vertices;
  const int n = topology.vertex_count;
  const std::vector<double> area = mixed_areas(mesh, topology);

  // sum_j (cot a + cot b)(v_j - v_i); eq. 3 takes its length, so the sign convention does not matter here.
  const std::vector<Eigen::Vector3d> mean_normal = cotangent_laplacian_sums(p, topology);
  std::vector<double> angle_sum(n, 0.0);
  std::vector<std::uint8_t> degenerate(mesh.triangles.size(), 0);
  for (int t : topology.degenerate_triangles) degenerate[t] = 1;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (degenerate[t]) continue;
    const Eigen::Vector3i& tri = mesh.triangles[t];
    for (int k = 0; k < 3; ++k) angle_sum[tri[k]] += corner_angle(p, tri[k], tri[(k + 1) % 3], tri[(k + 2) % 3]);
  }

  VertexCurvatures c;
  c.resize(n, false);
  for (int i = 0; i < n; ++i) {
    if (!topology.is_interior(i) || !(area[i] > 0.0)) continue;
    const double H = mean_normal[i].norm() / (4.0 * area[i]);
    const double K = (2.0 * std::numbers::pi - angle_sum[i]) / area[i];
    if (!std::isfinite(static_cast<float>(H)) || !std::isfinite(static_cast<float>(K))) continue;
    double k_max, k_min;
    principal_from_mean_gaussian(H, K, &k_max, &k_min);
    c.mean[i] = static_cast<float>(H);
    c.gaussian[i] = static_cast<float>(K);
    c.k_max[i] = static_cast<float>(k_max);
    c.k_min[i] = static_cast<float>(k_min);
    c.valid[i] = 1;
    ++c.valid_count;
  }
  return c;
}

}  // namespace hf::head
