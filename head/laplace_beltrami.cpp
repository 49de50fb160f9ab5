#include "head/laplace_beltrami.h"

#include <cmath>

namespace hf::head {

LaplaceBeltrami laplace_beltrami(const TriangleMesh& mesh, const MeshTopology& topology) {
  const std::vector<Eigen::Vector3f>& p = mesh.vertices;
  const int n = topology.vertex_count;
  const std::vector<Eigen::Vector3d> sum = cotangent_laplacian_sums(p, topology);  // 2 x sum_j w_ij (v_j - v_i)
  std::vector<double> S(n, 0.0);
  std::vector<std::uint8_t> degenerate(mesh.triangles.size(), 0);
  for (int t : topology.degenerate_triangles) degenerate[t] = 1;
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    if (degenerate[t]) continue;
    const double a = triangle_area(p, mesh.triangles[t]);
    for (int k = 0; k < 3; ++k) S[mesh.triangles[t][k]] += a;
  }
  LaplaceBeltrami out;
  out.delta.assign(n, Eigen::Vector3f::Zero());
  out.magnitude.assign(n, 0.0f);
  out.valid.assign(n, 0);
  for (int i = 0; i < n; ++i) {
    if (!topology.is_interior(i) || !(S[i] > 0.0)) continue;
    const Eigen::Vector3d delta = 0.5 * sum[i] / (S[i] / 3.0);
    const Eigen::Vector3f d = delta.cast<float>();
    const float m = static_cast<float>(delta.norm());
    if (!d.allFinite() || !std::isfinite(m)) continue;
    out.delta[i] = d;
    out.magnitude[i] = m;
    out.valid[i] = 1;
    ++out.valid_count;
  }
  return out;
}

}  // namespace hf::head
