#include "registration/ndt/ndt_cells.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

namespace hf {

std::uint64_t NdtGrid::key(long i, long j, long k) {
  // 21 bits per axis (offset binary): +-1e6 cells, +-100 km at 10 cm.
  const auto u = [](long v) { return std::uint64_t(v + (1L << 20)) & ((1ULL << 21) - 1); };
  return u(i) | (u(j) << 21) | (u(k) << 42);
}

bool NdtGrid::cell_index(const Eigen::Vector3d& p, long* i, long* j, long* k) const {
  if (!p.allFinite()) return false;
  const Eigen::Vector3d c = p / cell_m_;
  if (c.cwiseAbs().maxCoeff() > double(1L << 20) - 2.0) return false;
  *i = long(std::floor(c.x()));
  *j = long(std::floor(c.y()));
  *k = long(std::floor(c.z()));
  return true;
}

void NdtMoments::add(const Eigen::Vector3d& p, double weight, double colour) {
  w += weight;
  ++n;
  s += weight * p;
  ss += weight * p * p.transpose();
  sc += weight * colour;
  scc += weight * colour * colour;
}

void NdtGrid::add(const Eigen::Vector3d& p, double weight, double colour) {
  long i, j, k;
  if (finished_ || !(weight > 0.0) || !std::isfinite(weight) || !std::isfinite(colour) || !cell_index(p, &i, &j, &k)) {
    return;
  }
  moments_[key(i, j, k)].add(p, weight, colour);
}

bool NdtGrid::key_of(const Eigen::Vector3d& p, std::uint64_t* out) const {
  long i, j, k;
  if (!cell_index(p, &i, &j, &k)) return false;
  *out = key(i, j, k);
  return true;
}

void NdtGrid::insert(std::uint64_t k, const NdtCell& cell) {
  finished_ = true;
  if (index_.count(k) != 0) return;
  index_[k] = int(cells_.size());
  cells_.push_back(cell);
}

bool make_ndt_cell(const NdtMoments& m, const NdtGridOptions& options, NdtCell* cell) {
  if (m.n < options.min_points || m.n < 2 || !(m.w > 0.0)) return false;
  cell->count = m.n;
  cell->mean = m.s / m.w;
  cell->colour_mean = m.sc / m.w;
  cell->colour_var = std::max(0.0, m.scc / m.w - cell->colour_mean * cell->colour_mean);
  // Eq. 63 with weights: the unbiased (reliability-weight) form reduces to 1 / (K - 1) for unit weights.
  const double correction = double(m.n) / double(m.n - 1);
  const Eigen::Matrix3d cov = (m.ss / m.w - cell->mean * cell->mean.transpose()) * correction;
  return cell->mean.allFinite() && std::isfinite(cell->colour_var) && regularise_cell(cov, options, cell);
}

bool regularise_cell(const Eigen::Matrix3d& covariance, const NdtGridOptions& options, NdtCell* cell) {
  if (!covariance.allFinite()) return false;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (covariance + covariance.transpose()));
  if (es.info() != Eigen::Success) return false;
  Eigen::Vector3d lambda = es.eigenvalues();
  const double floor =
      std::max(options.eigenvalue_floor_ratio * std::max(lambda(2), 0.0), options.min_sigma_m * options.min_sigma_m);
  for (int a = 0; a < 3; ++a) lambda(a) = std::max(lambda(a), floor);
  const Eigen::Matrix3d& V = es.eigenvectors();
  cell->eigenvalues = lambda;
  cell->eigenvectors = V;
  cell->Sigma = V * lambda.asDiagonal() * V.transpose();
  cell->Sigma_inv = V * lambda.cwiseInverse().asDiagonal() * V.transpose();
  return cell->Sigma_inv.allFinite();
}

void NdtGrid::finish() {
  if (finished_) return;
  finished_ = true;
  // Deterministic order: by key.
  std::vector<std::uint64_t> keys;
  keys.reserve(moments_.size());
  for (const auto& [k, m] : moments_) {
    if (m.n >= options_.min_points) keys.push_back(k);
  }
  std::sort(keys.begin(), keys.end());
  cells_.reserve(keys.size());
  for (const std::uint64_t k : keys) {
    NdtCell cell;
    if (!make_ndt_cell(moments_[k], options_, &cell)) continue;
    index_[k] = int(cells_.size());
    cells_.push_back(cell);
  }
  moments_.clear();
}

const NdtCell* NdtGrid::find(const Eigen::Vector3d& p) const {
  long i, j, k;
  if (!cell_index(p, &i, &j, &k)) return nullptr;
  const auto it = index_.find(key(i, j, k));
  return it == index_.end() ? nullptr : &cells_[size_t(it->second)];
}

void NdtGrid::neighbourhood(const Eigen::Vector3d& p, int count, std::vector<const NdtCell*>* out) const {
  out->clear();
  long i, j, k;
  if (!cell_index(p, &i, &j, &k)) return;
  auto visit = [&](long di, long dj, long dk) {
    const auto it = index_.find(key(i + di, j + dj, k + dk));
    if (it != index_.end()) out->push_back(&cells_[size_t(it->second)]);
  };
  visit(0, 0, 0);
  if (count == 7) {
    for (int a = 0; a < 3; ++a) {
      for (const long d : {-1L, 1L}) visit(a == 0 ? d : 0, a == 1 ? d : 0, a == 2 ? d : 0);
    }
  } else if (count == 27) {
    for (long dk = -1; dk <= 1; ++dk)
      for (long dj = -1; dj <= 1; ++dj)
        for (long di = -1; di <= 1; ++di)
          if (di != 0 || dj != 0 || dk != 0) visit(di, dj, dk);
  }
}

NdtModel build_ndt_model(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& resolutions_m,
                         const NdtGridOptions& options) {
  NdtModel model;
  for (const double r : resolutions_m) {
    NdtGrid grid(r, options);
    for (const Eigen::Vector3d& p : points) grid.add(p);
    grid.finish();
    model.levels.push_back(std::move(grid));
  }
  return model;
}

}  // namespace hf
