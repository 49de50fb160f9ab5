#include "head/curvature.h"

#include <algorithm>
#include <cmath>
#include <tbb/parallel_for.h>

#include "mesh/k_ring.h"

namespace hf::head {

void VertexCurvatures::resize(int n, bool with_directions) {
  mean.assign(n, 0.0f);
  gaussian.assign(n, 0.0f);
  k_max.assign(n, 0.0f);
  k_min.assign(n, 0.0f);
  valid.assign(n, 0);
  dir_max.assign(with_directions ? n : 0, Eigen::Vector3f::Zero());
  dir_min.assign(with_directions ? n : 0, Eigen::Vector3f::Zero());
  valid_count = 0;
}

void principal_from_mean_gaussian(double H, double K, double* k_max, double* k_min) {
  const double disc = H * H - K;
  const double root = disc > 0.0 ? std::sqrt(disc) : 0.0;
  *k_max = H + root;
  *k_min = H - root;
}

void smooth_at_scale(const TriangleMesh& mesh, const MeshTopology& topology, double sigma,
                     const std::vector<std::uint8_t>& valid, std::vector<std::vector<float>*> fields) {
  if (!(sigma > 0.0) || fields.empty()) return;
  const int n = topology.vertex_count;
  std::vector<double> area(n, 0.0);
  for (int i = 0; i < n; ++i)
    for (int k = topology.triangle_offsets[i]; k < topology.triangle_offsets[i + 1]; ++k)
      area[i] += triangle_area(mesh.vertices, mesh.triangles[topology.vertex_triangles[k]]) / 3.0;
  double edge = 0.0;
  int edges = 0;
  for (const MeshEdge& e : topology.edges)
    if (e.triangle_count > 0) {
      edge += (mesh.vertices[e.v[0]] - mesh.vertices[e.v[1]]).cast<double>().norm();
      ++edges;
    }
  if (edges == 0 || !(edge > 0.0)) return;
  edge /= edges;
  const double reach = 2.5 * sigma;
  // A path of k edges spans at most k edges' lengths; 0.75 of the mean allows for the shorter edges.
  const int k = std::clamp(static_cast<int>(std::ceil(reach / (0.75 * edge))), 1, 64);
  std::vector<std::vector<float>> out(fields.size(), std::vector<float>(n, 0.0f));
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    KRing walker(topology);
    std::vector<int> ring;
    std::vector<double> sum(fields.size());
    for (int i = range.begin(); i != range.end(); ++i) {
      if (!valid[i]) continue;
      walker.collect(i, k, ring);
      std::fill(sum.begin(), sum.end(), 0.0);
      double weight = 0.0;
      const Eigen::Vector3d pi = mesh.vertices[i].cast<double>();
      for (int j : ring) {
        if (!valid[j]) continue;
        const double d2 = (mesh.vertices[j].cast<double>() - pi).squaredNorm();
        if (d2 > reach * reach) continue;
        const double w = area[j] * std::exp(-d2 / (2.0 * sigma * sigma));
        weight += w;
        for (size_t f = 0; f < fields.size(); ++f) sum[f] += w * (*fields[f])[j];
      }
      for (size_t f = 0; f < fields.size(); ++f)
        out[f][i] = weight > 0.0 ? static_cast<float>(sum[f] / weight) : (*fields[f])[i];
    }
  });
  for (size_t f = 0; f < fields.size(); ++f) *fields[f] = std::move(out[f]);
}

void smooth_at_scale(const TriangleMesh& mesh, const MeshTopology& topology, double sigma, VertexCurvatures& c) {
  smooth_at_scale(mesh, topology, sigma, c.valid, {&c.mean, &c.gaussian, &c.k_max, &c.k_min});
}

}  // namespace hf::head
