#include "mesh/topology.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <tuple>

namespace hf {
namespace {

struct HalfEdge {
  int a, b, triangle, opposite;  // a < b
};

// Groups the triangles' sides by their (sorted) vertex pair; one MeshEdge per pair.
void build_edges(const TriangleMesh& mesh, MeshTopology& topo) {
  std::vector<HalfEdge> half;
  half.reserve(mesh.triangles.size() * 3);
  for (int t = 0; t < static_cast<int>(mesh.triangles.size()); ++t) {
    const Eigen::Vector3i& tri = mesh.triangles[t];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2]) {
      topo.degenerate_triangles.push_back(t);
      continue;
    }
    for (int k = 0; k < 3; ++k) {
      const int a = tri[k], b = tri[(k + 1) % 3], c = tri[(k + 2) % 3];
      half.push_back({std::min(a, b), std::max(a, b), t, c});
    }
  }
  std::sort(half.begin(), half.end(), [](const HalfEdge& x, const HalfEdge& y) {
    return std::tie(x.a, x.b, x.triangle) < std::tie(y.a, y.b, y.triangle);
  });
  for (size_t i = 0; i < half.size();) {
    size_t j = i;
    MeshEdge e;
    e.v = {half[i].a, half[i].b};
    while (j < half.size() && half[j].a == half[i].a && half[j].b == half[i].b) {
      if (e.triangle_count < 2) {
        e.triangle[e.triangle_count] = half[j].triangle;
        e.opposite[e.triangle_count] = half[j].opposite;
      }
      ++e.triangle_count;
      ++j;
    }
    topo.edges.push_back(e);
    i = j;
  }
}

void build_rings(const TriangleMesh& mesh, MeshTopology& topo) {
  const int n = topo.vertex_count;
  topo.ring_offsets.assign(n + 1, 0);
  for (const MeshEdge& e : topo.edges) {
    ++topo.ring_offsets[e.v[0] + 1];
    ++topo.ring_offsets[e.v[1] + 1];
  }
  for (int i = 0; i < n; ++i) topo.ring_offsets[i + 1] += topo.ring_offsets[i];
  topo.ring.assign(topo.ring_offsets[n], -1);
  topo.ring_edges.assign(topo.ring_offsets[n], -1);
  std::vector<int> fill(topo.ring_offsets.begin(), topo.ring_offsets.end() - 1);
  // Edges are sorted by (v0, v1), so each vertex's neighbours arrive in ascending order only for the larger
  // endpoint; sort each ring afterwards together with its edge indices.
  for (int ei = 0; ei < static_cast<int>(topo.edges.size()); ++ei) {
    const MeshEdge& e = topo.edges[ei];
    for (int s = 0; s < 2; ++s) {
      const int at = fill[e.v[s]]++;
      topo.ring[at] = e.v[1 - s];
      topo.ring_edges[at] = ei;
    }
  }
  std::vector<std::pair<int, int>> scratch;
  for (int i = 0; i < n; ++i) {
    const int b = topo.ring_offsets[i], end = topo.ring_offsets[i + 1];
    scratch.clear();
    for (int k = b; k < end; ++k) scratch.emplace_back(topo.ring[k], topo.ring_edges[k]);
    std::sort(scratch.begin(), scratch.end());
    for (int k = b; k < end; ++k) std::tie(topo.ring[k], topo.ring_edges[k]) = scratch[k - b];
  }

  topo.triangle_offsets.assign(n + 1, 0);
  std::vector<std::uint8_t> degenerate(mesh.triangles.size(), 0);
  for (int t : topo.degenerate_triangles) degenerate[t] = 1;
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!degenerate[t])
      for (int k = 0; k < 3; ++k) ++topo.triangle_offsets[mesh.triangles[t][k] + 1];
  for (int i = 0; i < n; ++i) topo.triangle_offsets[i + 1] += topo.triangle_offsets[i];
  topo.vertex_triangles.assign(topo.triangle_offsets[n], -1);
  std::vector<int> tfill(topo.triangle_offsets.begin(), topo.triangle_offsets.end() - 1);
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    if (!degenerate[t])
      for (int k = 0; k < 3; ++k) topo.vertex_triangles[tfill[mesh.triangles[t][k]]++] = static_cast<int>(t);
}

void classify(MeshTopology& topo) {
  topo.boundary_vertex.assign(topo.vertex_count, 0);
  topo.non_manifold_vertex.assign(topo.vertex_count, 0);
  for (const MeshEdge& e : topo.edges) {
    if (e.is_boundary()) {
      ++topo.boundary_edge_count;
      topo.boundary_vertex[e.v[0]] = topo.boundary_vertex[e.v[1]] = 1;
    } else if (!e.is_manifold()) {
      ++topo.non_manifold_edge_count;
      topo.non_manifold_vertex[e.v[0]] = topo.non_manifold_vertex[e.v[1]] = 1;
    }
  }
  for (int i = 0; i < topo.vertex_count; ++i)
    if (topo.degree(i) == 0) ++topo.isolated_vertex_count;
}

}  // namespace

MeshTopology build_topology(const TriangleMesh& mesh) {
  mesh.validate();
  MeshTopology topo;
  topo.vertex_count = static_cast<int>(mesh.vertices.size());
  build_edges(mesh, topo);
  build_rings(mesh, topo);
  classify(topo);
  return topo;
}

double corner_angle(const std::vector<Eigen::Vector3f>& p, int apex, int a, int b) {
  const Eigen::Vector3d u = (p[a] - p[apex]).cast<double>(), v = (p[b] - p[apex]).cast<double>();
  const double nu = u.norm(), nv = v.norm();
  if (nu == 0.0 || nv == 0.0) return 0.0;
  // atan2 of |u x v| and u . v is accurate for angles near 0 and pi, where acos of the cosine is not.
  return std::atan2(u.cross(v).norm(), u.dot(v));
}

double corner_cotangent(const std::vector<Eigen::Vector3f>& p, int apex, int a, int b) {
  const Eigen::Vector3d u = (p[a] - p[apex]).cast<double>(), v = (p[b] - p[apex]).cast<double>();
  const double sine = u.cross(v).norm();
  // A sliver's cotangent grows without bound; below this relative sine the corner is treated as degenerate.
  if (!(sine > 1e-12 * u.squaredNorm() + 1e-300) || !(sine > 1e-12 * v.squaredNorm() + 1e-300)) return 0.0;
  return u.dot(v) / sine;
}

double triangle_area(const std::vector<Eigen::Vector3f>& p, const Eigen::Vector3i& t) {
  const Eigen::Vector3d u = (p[t[1]] - p[t[0]]).cast<double>(), v = (p[t[2]] - p[t[0]]).cast<double>();
  return 0.5 * u.cross(v).norm();
}

double edge_cotangent_weight(const std::vector<Eigen::Vector3f>& p, const MeshEdge& e) {
  double w = 0.0;
  for (int s = 0; s < 2 && s < e.triangle_count; ++s) w += corner_cotangent(p, e.opposite[s], e.v[0], e.v[1]);
  return w;
}

std::vector<Eigen::Vector3d> cotangent_laplacian_sums(const std::vector<Eigen::Vector3f>& p,
                                                      const MeshTopology& topology) {
  std::vector<Eigen::Vector3d> sum(topology.vertex_count, Eigen::Vector3d::Zero());
  for (const MeshEdge& e : topology.edges) {
    const double w = edge_cotangent_weight(p, e);
    const Eigen::Vector3d d = (p[e.v[1]] - p[e.v[0]]).cast<double>();
    sum[e.v[0]] += w * d;
    sum[e.v[1]] -= w * d;
  }
  return sum;
}

}  // namespace hf
