#include "head/mls_curvature.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <tbb/parallel_for.h>

#include "mesh/k_ring.h"

namespace hf::head {
namespace {

// +1 when the winding makes face normals point away from the centroid on the whole, -1 otherwise.
double outward_sign(const TriangleMesh& mesh) {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3f& v : mesh.vertices) centroid += v.cast<double>();
  if (!mesh.vertices.empty()) centroid /= static_cast<double>(mesh.vertices.size());
  double volume6 = 0.0;  // six times the signed volume of the tetrahedra (centroid, triangle)
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>() - centroid;
    const Eigen::Vector3d b = mesh.vertices[t[1]].cast<double>() - centroid;
    const Eigen::Vector3d c = mesh.vertices[t[2]].cast<double>() - centroid;
    volume6 += a.dot(b.cross(c));
  }
  return volume6 < 0.0 ? -1.0 : 1.0;
}

struct LocalFit {
  bool ok = false;
  double H = 0, K = 0, k_max = 0, k_min = 0;
  Eigen::Vector3d dir_max = Eigen::Vector3d::Zero(), dir_min = Eigen::Vector3d::Zero();
};

// Step 3-4 for one vertex: fit over `ring` (positions relative to v_i), then the shape operator at the origin.
LocalFit fit_vertex(const std::vector<Eigen::Vector3f>& p, int i, const std::vector<int>& ring,
                    const Eigen::Vector3d& n, double h) {
  LocalFit out;
  const int m = static_cast<int>(ring.size());
  const int terms = m >= 10 ? 10 : (m >= 6 ? 6 : 0);
  if (terms == 0 || !(h > 0.0)) return out;
  Eigen::Vector3d e1 = n.unitOrthogonal();
  Eigen::Vector3d e2 = n.cross(e1);
  Eigen::MatrixXd A(m, terms);
  Eigen::VectorXd f(m);
  const Eigen::Vector3d vi = p[i].cast<double>();
  for (int r = 0; r < m; ++r) {
    const Eigen::Vector3d d = p[ring[r]].cast<double>() - vi;
    const double x = d.dot(e1) / h, y = d.dot(e2) / h, z = d.dot(n) / h;
    const double sw = std::sqrt(std::exp(-d.squaredNorm() / (h * h)));  // row weight sqrt(theta)
    double b[10] = {1, x, y, x * x, x * y, y * y, x * x * x, x * x * y, x * y * y, y * y * y};
    for (int c = 0; c < terms; ++c) A(r, c) = sw * b[c];
    f(r) = sw * z;
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(1e-10);
  if (qr.rank() < terms) return out;
  const Eigen::VectorXd c = qr.solve(f);
  if (!c.allFinite()) return out;
  // Derivatives of the height z(x, y) in mesh units at the origin: z = h P(x/h, y/h).
  const double pu = c(1), pv = c(2);
  const double puu = 2.0 * c(3) / h, puv = c(4) / h, pvv = 2.0 * c(5) / h;
  const double E = 1 + pu * pu, F = pu * pv, G = 1 + pv * pv, w = std::sqrt(1 + pu * pu + pv * pv);
  // Second fundamental form of F = z - p: F_ij / |grad F| with F_ij = -p_ij.
  const double L = -puu / w, M = -puv / w, N = -pvv / w;
  const double det = E * G - F * F;
  out.H = (E * N - 2 * F * M + G * L) / (2 * det);
  out.K = (L * N - M * M) / det;
  principal_from_mean_gaussian(out.H, out.K, &out.k_max, &out.k_min);
  // Shape operator S = I^-1 II in (u, v); its eigenvectors mapped to 3-D through the tangent basis.
  Eigen::Matrix2d I, II;
  I << E, F, F, G;
  II << L, M, M, N;
  const Eigen::Matrix2d S = I.inverse() * II;
  const Eigen::Vector3d ru = e1 + pu * n, rv = e2 + pv * n;
  auto direction = [&](double k) {
    // (S - k I) a = 0: a is orthogonal to the larger row of S - k I; any tangent when S = k I (an umbilic).
    const Eigen::Matrix2d D = S - k * Eigen::Matrix2d::Identity();
    Eigen::Vector2d row = D.row(0).norm() >= D.row(1).norm() ? Eigen::Vector2d(D.row(0)) : Eigen::Vector2d(D.row(1));
    Eigen::Vector2d a = row.norm() > 1e-12 * (std::abs(k) + 1e-300) ? Eigen::Vector2d(-row(1), row(0))
                                                                    : Eigen::Vector2d(1, 0);
    Eigen::Vector3d t = a(0) * ru + a(1) * rv;
    return Eigen::Vector3d(t.norm() > 0 ? t.normalized() : e1);
  };
  out.dir_max = direction(out.k_max);
  out.dir_min = out.dir_max.cross(ru.cross(rv).normalized()).normalized();
  out.ok = std::isfinite(static_cast<float>(out.H)) && std::isfinite(static_cast<float>(out.K)) &&
           std::isfinite(static_cast<float>(out.k_max)) && std::isfinite(static_cast<float>(out.k_min)) &&
           out.dir_max.allFinite() && out.dir_min.allFinite();
  return out;
}

}  // namespace

std::vector<Eigen::Vector3f> mls_vertex_normals(const TriangleMesh& mesh, const MeshTopology& topology) {
  const double sign = outward_sign(mesh);
  std::vector<Eigen::Vector3d> sum(topology.vertex_count, Eigen::Vector3d::Zero());
  for (int i = 0; i < topology.vertex_count; ++i)
    for (int k = topology.triangle_offsets[i]; k < topology.triangle_offsets[i + 1]; ++k) {
      const Eigen::Vector3i& t = mesh.triangles[topology.vertex_triangles[k]];
      const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>();
      const Eigen::Vector3d nrm = (mesh.vertices[t[1]].cast<double>() - a).cross(mesh.vertices[t[2]].cast<double>() - a);
      const double len = nrm.norm();
      if (len > 0.0) sum[i] += nrm / len;
    }
  std::vector<Eigen::Vector3f> out(topology.vertex_count, Eigen::Vector3f::Zero());
  for (int i = 0; i < topology.vertex_count; ++i) {
    const double len = sum[i].norm();
    if (len > 1e-12) out[i] = (sign * sum[i] / len).cast<float>();
  }
  return out;
}

VertexCurvatures mls_curvature(const TriangleMesh& mesh, const MeshTopology& topology, const MlsOptions& options,
                               const std::vector<std::uint8_t>& only) {
  const int n = topology.vertex_count;
  const std::vector<Eigen::Vector3f> normals = mls_vertex_normals(mesh, topology);
  VertexCurvatures c;
  c.resize(n, true);
  const int k = options.k < 1 ? 1 : options.k;
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 256), [&](const tbb::blocked_range<int>& range) {
    KRing walker(topology);
    std::vector<int> ring;
    for (int i = range.begin(); i != range.end(); ++i) {
      if (!only.empty() && !only[i]) continue;
      if (!topology.is_interior(i) || normals[i].squaredNorm() == 0.0f) continue;
      double h = 0.0;
      for (const int* j = topology.ring_begin(i); j != topology.ring_end(i); ++j)
        h += (mesh.vertices[*j] - mesh.vertices[i]).cast<double>().norm();
      h /= topology.degree(i);
      int rings = k;
      if (options.h > 0.0) {
        rings = std::max(k, std::min(64, static_cast<int>(std::ceil(2.0 * options.h / (0.75 * h)))));
        h = options.h;
      }
      walker.collect(i, rings, ring);
      const LocalFit fit = fit_vertex(mesh.vertices, i, ring, normals[i].cast<double>(), h);
      if (!fit.ok) continue;
      c.mean[i] = static_cast<float>(fit.H);
      c.gaussian[i] = static_cast<float>(fit.K);
      c.k_max[i] = static_cast<float>(fit.k_max);
      c.k_min[i] = static_cast<float>(fit.k_min);
      c.dir_max[i] = fit.dir_max.cast<float>();
      c.dir_min[i] = fit.dir_min.cast<float>();
      c.valid[i] = 1;
    }
  });
  for (int i = 0; i < n; ++i) c.valid_count += c.valid[i];
  return c;
}

}  // namespace hf::head
