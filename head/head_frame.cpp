#include "head/head_frame.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

#include "head/mls_curvature.h"

#include "core/error.h"

namespace hf::head {
namespace {

struct Pca {
  Eigen::Vector3d centroid;
  Eigen::Matrix3d axes;  // columns, descending variance
  double rms_radius = 0;
};

// Stage 1.
Pca surface_pca(const TriangleMesh& mesh) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double total = 0;
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          d = mesh.vertices[t[2]].cast<double>();
    const double area = 0.5 * (b - a).cross(d - a).norm();
    c += area * (a + b + d) / 3.0;
    total += area;
  }
  if (!(total > 0)) throw Error("head frame: the mesh has no triangle with positive area");
  c /= total;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const Eigen::Vector3i& t : mesh.triangles) {
    const Eigen::Vector3d a = mesh.vertices[t[0]].cast<double>(), b = mesh.vertices[t[1]].cast<double>(),
                          d = mesh.vertices[t[2]].cast<double>();
    const double area = 0.5 * (b - a).cross(d - a).norm();
    const Eigen::Vector3d m = (a + b + d) / 3.0 - c;
    cov += area * m * m.transpose();
  }
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / total);
  Pca p;
  p.centroid = c;
  p.rms_radius = std::sqrt(std::max(0.0, (cov / total).trace()));
  for (int k = 0; k < 3; ++k) p.axes.col(k) = eig.eigenvectors().col(2 - k);
  return p;
}

struct Plane {
  Eigen::Vector3d n;
  double d = 0;
  double rms = std::numeric_limits<double>::infinity();
};

// Stage 2, from one start.
Plane fit_symmetry(const std::vector<Eigen::Vector3d>& pts, Plane plane, int iterations) {
  const size_t n = pts.size();
  std::vector<std::pair<double, size_t>> match(n);
  for (int it = 0; it < iterations; ++it) {
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector3d r = pts[i] - 2.0 * (plane.n.dot(pts[i]) - plane.d) * plane.n;
      double best = std::numeric_limits<double>::infinity();
      size_t arg = 0;
      for (size_t j = 0; j < n; ++j) {
        const double d2 = (pts[j] - r).squaredNorm();
        if (d2 < best) {
          best = d2;
          arg = j;
        }
      }
      match[i] = {best, arg};
    }
    std::vector<double> d2s(n);
    for (size_t i = 0; i < n; ++i) d2s[i] = match[i].first;
    const size_t keep = std::max<size_t>(3, n * 8 / 10);
    std::nth_element(d2s.begin(), d2s.begin() + static_cast<long>(keep - 1), d2s.end());
    const double cut = d2s[keep - 1];
    Eigen::Matrix3d S = Eigen::Matrix3d::Zero();
    double sum_d2 = 0;
    size_t used = 0;
    for (size_t i = 0; i < n; ++i) {
      if (match[i].first > cut) continue;
      const Eigen::Vector3d diff = pts[i] - pts[match[i].second];
      S += diff * diff.transpose();
      sum_d2 += match[i].first;
      ++used;
    }
    plane.rms = std::sqrt(sum_d2 / std::max<size_t>(used, 1));
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(S);
    Eigen::Vector3d normal = eig.eigenvectors().col(2);
    // Pairs that straddle the plane give a strong p - q; if all pairs lie on the plane, keep the old normal.
    if (!(eig.eigenvalues()(2) > 0) || !normal.allFinite()) break;
    if (normal.dot(plane.n) < 0) normal = -normal;
    double dsum = 0;
    for (size_t i = 0; i < n; ++i)
      if (match[i].first <= cut) dsum += normal.dot(0.5 * (pts[i] + pts[match[i].second]));
    plane.n = normal;
    plane.d = dsum / std::max<size_t>(used, 1);
  }
  return plane;
}

// Vertices bucketed in a uniform grid of cell `cell`, for ball queries.
class PointGrid {
 public:
  PointGrid(const std::vector<Eigen::Vector3f>& pts, const std::vector<int>& ids, double cell) : pts_(pts), cell_(cell) {
    for (int i : ids) cells_[key(pts[i].cast<double>())].push_back(i);
  }
  template <class Fn>
  void ball(const Eigen::Vector3d& c, double r, Fn fn) const {
    const Eigen::Vector3i lo = index(c - Eigen::Vector3d::Constant(r)), hi = index(c + Eigen::Vector3d::Constant(r));
    for (int x = lo.x(); x <= hi.x(); ++x)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int z = lo.z(); z <= hi.z(); ++z) {
          auto it = cells_.find(pack({x, y, z}));
          if (it == cells_.end()) continue;
          for (int i : it->second)
            if ((pts_[i].cast<double>() - c).squaredNorm() <= r * r) fn(i);
        }
  }

 private:
  Eigen::Vector3i index(const Eigen::Vector3d& p) const {
    return (p / cell_).array().floor().cast<int>();
  }
  static std::uint64_t pack(const Eigen::Vector3i& c) {
    return (static_cast<std::uint64_t>(c.x() & 0x1fffff) << 42) | (static_cast<std::uint64_t>(c.y() & 0x1fffff) << 21) |
           static_cast<std::uint64_t>(c.z() & 0x1fffff);
  }
  std::uint64_t key(const Eigen::Vector3d& p) const { return pack(index(p)); }
  const std::vector<Eigen::Vector3f>& pts_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

// Stage 3's score of one candidate: the surface's fall-away from the tangent plane at scale rho, as a curvature
// 2 (p - q).n / |p - q|^2 averaged over the points q of the annulus rho/2 .. rho in each of 8 angular sectors, and
// the least of the sectors. High only where the surface falls away in every direction (a cap such as the nose
// tip); about 0 along a ridge (a neck stump's cut, a bust's base, a crown's rim); -inf when a sector is empty (an
// open mesh's border).
double cap_score(const std::vector<Eigen::Vector3f>& p, const std::vector<Eigen::Vector3f>& normals, const PointGrid& grid,
                 int i, double rho, const Eigen::Vector3d& across, Eigen::Vector3d* normal_out) {
  const Eigen::Vector3d c = p[i].cast<double>();
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  grid.ball(c, 0.5 * rho, [&](int j) { n += normals[j].cast<double>(); });
  if (!(n.norm() > 0)) return -std::numeric_limits<double>::infinity();
  n.normalize();
  *normal_out = n;
  // Sectors start at the symmetry plane's normal projected into the tangent plane, so the score does not depend
  // on the input's pose (a coordinate-based perpendicular would rotate the sectors with the input).
  Eigen::Vector3d e1 = across - across.dot(n) * n;
  e1 = e1.norm() > 1e-6 ? Eigen::Vector3d(e1.normalized()) : n.unitOrthogonal();
  const Eigen::Vector3d e2 = n.cross(e1);
  constexpr int kSectors = 8;
  double sum[kSectors] = {}, count[kSectors] = {};
  grid.ball(c, rho, [&](int j) {
    const Eigen::Vector3d d = p[j].cast<double>() - c;
    const double r2 = d.squaredNorm();
    if (r2 < 0.25 * rho * rho) return;
    const double angle = std::atan2(d.dot(e2), d.dot(e1));
    const int s = std::min(kSectors - 1, static_cast<int>((angle + std::numbers::pi) / (2 * std::numbers::pi) * kSectors));
    sum[s] += -2.0 * d.dot(n) / r2;
    count[s] += 1;
  });
  double score = std::numeric_limits<double>::infinity();
  for (int s = 0; s < kSectors; ++s) {
    if (count[s] == 0) return -std::numeric_limits<double>::infinity();
    score = std::min(score, sum[s] / count[s]);
  }
  return score;
}

double mean_edge_length(const TriangleMesh& mesh, const MeshTopology& topology) {
  double sum = 0;
  for (const MeshEdge& e : topology.edges) sum += (mesh.vertices[e.v[0]] - mesh.vertices[e.v[1]]).cast<double>().norm();
  return topology.edges.empty() ? 0.0 : sum / topology.edges.size();
}

}  // namespace

HeadFrame find_head_frame(const TriangleMesh& mesh, const MeshTopology& topology, const HeadFrameOptions& options) {
  std::vector<int> used;
  for (int i = 0; i < topology.vertex_count; ++i)
    if (!topology.is_isolated(i)) used.push_back(i);
  if (used.size() < 50)
    throw Error("head frame: " + std::to_string(used.size()) + " vertices in triangles (expected at least 50)");
  HeadFrame frame;
  frame.mean_edge_length = mean_edge_length(mesh, topology);
  const double h = frame.mean_edge_length;
  if (!(h > 0)) throw Error("head frame: every edge has zero length");
  const Pca pca = surface_pca(mesh);

  // Stage 2.
  std::vector<Eigen::Vector3d> samples;
  const size_t stride = std::max<size_t>(1, used.size() / std::max(options.symmetry_samples, 10));
  for (size_t k = 0; k < used.size(); k += stride) samples.push_back(mesh.vertices[used[k]].cast<double>());
  Plane best;
  for (int a = 0; a < 3; ++a) {
    Plane start;
    start.n = pca.axes.col(a);
    start.d = start.n.dot(pca.centroid);
    const Plane p = fit_symmetry(samples, start, options.symmetry_iterations);
    if (p.rms < best.rms) best = p;
  }
  frame.symmetry_rms_edges = best.rms / h;
  const Eigen::Vector3d x_axis = best.n;

  // Stage 3: the candidates near the plane, scored at scale rho.
  // The scale comes from the surface's RMS radius about its centroid (rotation invariant, unlike a bounding
  // box).
  const double rho = std::max(options.cap_scale * pca.rms_radius, 3.0 * h);
  const std::vector<Eigen::Vector3f> normals = mls_vertex_normals(mesh, topology);
  const PointGrid grid(mesh.vertices, used, rho);
  const double band = std::max(options.band_edges * h, 0.01 * rho);
  int tip = -1;
  double tip_score = -std::numeric_limits<double>::infinity();
  Eigen::Vector3d tip_normal = Eigen::Vector3d::Zero();
  for (int i : used) {
    if (std::abs(x_axis.dot(mesh.vertices[i].cast<double>()) - best.d) > band) continue;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    // Two scales: at rho the nose and the chin are both caps; at rho / 2 the nose's smaller radius sets it
    // apart (measured on Igea and Nefertiti, where rho alone picks the chin once in a while).
    // The small scale needs a few rings of vertices in its annulus; on coarse meshes it is left out.
    double score = cap_score(mesh.vertices, normals, grid, i, rho, x_axis, &n);
    if (0.5 * rho >= 2.5 * h && std::isfinite(score)) {
      Eigen::Vector3d unused = Eigen::Vector3d::Zero();
      const double small = cap_score(mesh.vertices, normals, grid, i, 0.5 * rho, x_axis, &unused);
      if (std::isfinite(small)) score += small;
    }
    if (score > tip_score) {
      tip_score = score;
      tip = i;
      tip_normal = n;
    }
  }
  if (tip < 0 || !std::isfinite(tip_score))
    throw Error("head frame: no vertex near the symmetry plane has a closed neighbourhood to score");
  frame.cap_score_edges = tip_score * h;
  frame.cap_scale = rho;
  Eigen::Vector3d y_axis = tip_normal - tip_normal.dot(x_axis) * x_axis;
  if (!(y_axis.norm() > 1e-6)) throw Error("head frame: the nose tip's normal lies across the symmetry plane");
  y_axis.normalize();
  // The cap score is flat across the tip's few central vertices, so a rigid motion's rounding could pick another
  // of them; the foremost vertex near the plane within rho / 2 along y is well separated (the tip's curvature).
  {
    const Eigen::Vector3d c = mesh.vertices[tip].cast<double>();
    double far = -std::numeric_limits<double>::infinity();
    int refined = tip;
    grid.ball(c, 0.5 * rho, [&](int j) {
      const Eigen::Vector3d p = mesh.vertices[j].cast<double>();
      if (std::abs(x_axis.dot(p) - best.d) > band) return;
      if (y_axis.dot(p - c) > far) {
        far = y_axis.dot(p - c);
        refined = j;
      }
    });
    tip = refined;
  }
  frame.nose_tip_vertex = tip;

  // Stage 4: two cues for which side of the tip is up, the more decisive one wins (measured on the four meshes
  // of ../shared/data/head_meshes, each cue alone is wrong on one of them, and there the other is far clearer):
  //   recession: the profile 1 .. 3 rho away from the tip lies farther behind it above (the nasion, the
  //     forehead) than below (the lips and the chin stand out almost as far as the nose);
  //   width: the head is wider 1 .. 2.5 rho above the tip (temples, eyes, the ears' tops) than as far below (jaw).
  Eigen::Vector3d z_axis = x_axis.cross(y_axis);
  const Eigen::Vector3d tip_p = mesh.vertices[tip].cast<double>();
  double recession[2] = {0, 0}, counted[2] = {0, 0};  // side 0: +z, side 1: -z
  grid.ball(tip_p, 3.0 * rho, [&](int j) {
    const Eigen::Vector3d d = mesh.vertices[j].cast<double>() - tip_p;
    if (std::abs(d.dot(x_axis)) > band) return;
    const double t = d.dot(z_axis);
    if (std::abs(t) < rho) return;
    recession[t > 0 ? 0 : 1] += -d.dot(y_axis);
    counted[t > 0 ? 0 : 1] += 1;
  });
  double width_lo[2] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max()};
  double width_hi[2] = {-std::numeric_limits<double>::max(), -std::numeric_limits<double>::max()};
  for (int i : used) {
    const Eigen::Vector3d d = mesh.vertices[i].cast<double>() - tip_p;
    const double t = d.dot(z_axis);
    if (std::abs(t) < rho || std::abs(t) > 2.5 * rho) continue;
    const int side = t > 0 ? 0 : 1;
    width_lo[side] = std::min(width_lo[side], d.dot(x_axis));
    width_hi[side] = std::max(width_hi[side], d.dot(x_axis));
  }
  const double tiny = 1e-9 * h;
  double width[2], rec[2];
  for (int side = 0; side < 2; ++side) {
    width[side] = std::max(tiny, width_hi[side] - width_lo[side]);
    rec[side] = std::max(tiny, counted[side] > 0 ? recession[side] / counted[side] : 0.0);
  }
  // Each cue as (a - b) / (|a| + |b|) in [-1, 1]: for positive a, b this is tanh(log(a / b) / 2), the same order of
  // decisiveness as the log ratio, but a profile that does not recede on one side (a mean recession <= 0, common
  // on a noisy fused head whose tip is not quite the foremost point) no longer gives a near-infinite vote.
  const auto cue = [](double a, double b) { return std::abs(a) + std::abs(b) > 0 ? (a - b) / (std::abs(a) + std::abs(b)) : 0.0; };
  const double width_vote = cue(width_hi[0] - width_lo[0] > 0 ? width_hi[0] - width_lo[0] : 0.0,
                                width_hi[1] - width_lo[1] > 0 ? width_hi[1] - width_lo[1] : 0.0);  // > 0: +z is up
  const double recession_vote = cue(counted[0] > 0 ? recession[0] / counted[0] : 0.0,
                                    counted[1] > 0 ? recession[1] / counted[1] : 0.0);  // > 0: +z recedes more: up
  const double vote = std::abs(width_vote) > std::abs(recession_vote) ? width_vote : recession_vote;
  const bool flip = vote < 0;
  if (flip) z_axis = -z_axis;
  frame.recession_above = (flip ? rec[1] : rec[0]) / h;
  frame.recession_below = (flip ? rec[0] : rec[1]) / h;
  frame.width_above = (flip ? width[1] : width[0]) / h;
  frame.width_below = (flip ? width[0] : width[1]) / h;
  const Eigen::Vector3d x_final = y_axis.cross(z_axis);

  frame.R_head_input.row(0) = x_final.transpose();
  frame.R_head_input.row(1) = y_axis.transpose();
  frame.R_head_input.row(2) = z_axis.transpose();
  frame.origin_input = mesh.vertices[frame.nose_tip_vertex].cast<double>();
  frame.scale = 1.0 / h;
  return frame;
}

}  // namespace hf::head
