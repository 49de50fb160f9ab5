#include "slam/appearance/eigenspaces.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"

namespace hf::slam {
namespace {

using Eigenspace = EigenspacesIndex::Eigenspace;

// An eigenspace while it is built (double); the index keeps it in float (Eigenspace).
struct Space {
  Eigen::VectorXd mean;
  Eigen::MatrixXd basis;
};

Eigenspace stored(const Space& s) { return Eigenspace{s.mean.cast<float>(), s.basis.cast<float>()}; }

// The thumbnails as columns of a D x N matrix (double: PCA and residuals accumulate in double).
struct Thumbnails {
  Eigen::MatrixXd X;
  size_t count() const { return size_t(X.cols()); }
};

// Coefficients c = E^T (x - mu) and squared residual ||x - mu||^2 - ||c||^2 (clamped: rounding can make it
// slightly negative), in double whatever the storage.
template <class S>
double residual_in(const S& s, const Eigen::VectorXd& x, Eigen::VectorXd* coefficients = nullptr) {
  const Eigen::VectorXd y = x - s.mean.template cast<double>();
  const Eigen::VectorXd c = s.basis.template cast<double>().transpose() * y;
  if (coefficients) *coefficients = c;
  return std::max(0.0, y.squaredNorm() - c.squaredNorm());
}

// The PCA eigenspace of `members`: their mean, and the eigenvectors of their scatter with the largest eigenvalues,
// computed from the M x M Gram matrix (M << D). Dimension: the smallest d <= d_max (and <= the rank) at which every
// member's squared residual is below theta, else the cap.
Space fit_eigenspace(const Thumbnails& t, const std::vector<size_t>& members, int d_max, double theta) {
  const Eigen::Index D = t.X.rows(), M = Eigen::Index(members.size());
  Space s;
  s.mean = Eigen::VectorXd::Zero(D);
  for (size_t m : members) s.mean += t.X.col(Eigen::Index(m));
  s.mean /= double(M);
  Eigen::MatrixXd A(D, M);
  for (Eigen::Index j = 0; j < M; ++j) A.col(j) = t.X.col(Eigen::Index(members[size_t(j)])) - s.mean;
  const Eigen::MatrixXd G = A.transpose() * A;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(G);
  const Eigen::VectorXd& lambda = eig.eigenvalues();  // ascending
  const double floor = 1e-10 * std::max(1e-300, G.trace());
  int rank = 0;
  while (rank < M && lambda(M - 1 - rank) > floor) ++rank;
  const int cap = std::min(d_max, rank);
  // residual_i(d) = G_ii - sum_{k<d} lambda_k v_k[i]^2
  Eigen::VectorXd r = G.diagonal();
  int d = 0;
  while (d < cap && r.maxCoeff() >= theta) {
    const Eigen::Index k = M - 1 - d;
    r -= lambda(k) * eig.eigenvectors().col(k).cwiseAbs2();
    ++d;
  }
  s.basis.resize(D, d);
  for (int k = 0; k < d; ++k) {
    const Eigen::Index c = M - 1 - k;
    s.basis.col(k) = A * eig.eigenvectors().col(c) / std::sqrt(lambda(c));
  }
  return s;
}

// An image no eigenspace explains within theta is stored raw, as MDL prefers: a 0-dimensional eigenspace whose
// mean is the image (residual 0 for it; ||x_q - x||^2 for a query, the thumbnail distance).
Space raw_eigenspace(const Eigen::VectorXd& x) { return Space{x, Eigen::MatrixXd(x.size(), 0)}; }

struct Hypothesis {
  std::vector<size_t> members;  // sorted
  Space space;
  std::vector<double> residuals;  // of the members, same order
};

// Eigenspace growing from one seed (step 2 of the header).
Hypothesis grow(const Thumbnails& t, std::vector<size_t> members, const EigenspacesOptions& o, double theta) {
  std::sort(members.begin(), members.end());
  std::vector<bool> in(t.count(), false);
  for (size_t m : members) in[m] = true;
  Space space = fit_eigenspace(t, members, o.max_dimension, theta);
  for (;;) {
    std::vector<std::pair<double, size_t>> candidates;
    for (size_t j = 0; j < t.count(); ++j) {
      if (in[j]) continue;
      const double r = residual_in(space, t.X.col(Eigen::Index(j)));
      if (r < theta) candidates.push_back({r, j});
    }
    if (candidates.empty()) break;
    std::sort(candidates.begin(), candidates.end());
    const size_t take = std::min(candidates.size(), std::max<size_t>(1, members.size() / 4));
    for (size_t c = 0; c < take; ++c) {
      in[candidates[c].second] = true;
      members.push_back(candidates[c].second);
    }
    std::sort(members.begin(), members.end());
    space = fit_eigenspace(t, members, o.max_dimension, theta);
  }
  Hypothesis h{members, std::move(space), {}};
  for (size_t m : h.members) h.residuals.push_back(residual_in(h.space, t.X.col(Eigen::Index(m))));
  return h;
}

// Step 1: seeds spread evenly over the index, each a keyframe and its nearest thumbnails.
std::vector<std::vector<size_t>> make_seeds(const Thumbnails& t, const EigenspacesOptions& o) {
  const size_t n = t.count();
  const size_t seeds = std::min(n, size_t(o.max_seeds));
  const size_t size = std::min(n, size_t(o.seed_size));
  std::vector<std::vector<size_t>> out;
  for (size_t s = 0; s < seeds; ++s) {
    const size_t centre = s * n / seeds;
    std::vector<std::pair<double, size_t>> by_distance;
    for (size_t j = 0; j < n; ++j)
      by_distance.push_back({(t.X.col(Eigen::Index(j)) - t.X.col(Eigen::Index(centre))).squaredNorm(), j});
    std::partial_sort(by_distance.begin(), by_distance.begin() + Eigen::Index(size), by_distance.end());
    std::vector<size_t> seed;
    for (size_t k = 0; k < size; ++k) seed.push_back(by_distance[k].second);
    out.push_back(seed);
  }
  return out;
}

// Step 3: greedy MDL selection; returns the indices of the selected hypotheses.
std::vector<size_t> select_mdl(const std::vector<Hypothesis>& hs, size_t n, double D, double norm2,
                               double error_cost) {
  std::vector<bool> covered(n, false), taken(hs.size(), false);
  std::vector<size_t> selected;
  for (;;) {
    double best = 0.0;
    size_t best_h = hs.size();
    for (size_t h = 0; h < hs.size(); ++h) {
      if (taken[h]) continue;
      const double d = double(hs[h].space.basis.cols());
      double saving = -(d + 1.0) * D;
      for (size_t i = 0; i < hs[h].members.size(); ++i)
        if (!covered[hs[h].members[i]]) saving += D - d - error_cost * D * hs[h].residuals[i] / norm2;
      if (saving > best) {
        best = saving;
        best_h = h;
      }
    }
    if (best_h == hs.size()) break;
    taken[best_h] = true;
    selected.push_back(best_h);
    for (size_t m : hs[best_h].members) covered[m] = true;
  }
  return selected;
}

// Step 4's rule: the eigenspace with the smallest residual (ties: the smaller index).
template <class S>
size_t best_space(const std::vector<S>& spaces, const Eigen::VectorXd& x, double* residual) {
  size_t best = 0;
  double best_r = std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < spaces.size(); ++j) {
    const double r = residual_in(spaces[j], x);
    if (r < best_r) {
      best_r = r;
      best = j;
    }
  }
  if (residual) *residual = best_r;
  return best;
}

}  // namespace

void EigenspacesOptions::validate() const {
  thumbnail.validate();
  auto fail = [](const std::string& what) { throw Error("eigenspaces: " + what); };
  if (max_dimension < 0 || max_dimension > 64) fail("max_dimension must be 0..64");
  if (!(std::isfinite(residual_fraction) && residual_fraction > 0.0)) fail("residual_fraction must be > 0");
  if (seed_size < 1 || seed_size > 64) fail("seed_size must be 1..64");
  if (max_seeds < 1 || max_seeds > 4096) fail("max_seeds must be 1..4096");
  if (!(std::isfinite(error_cost) && error_cost >= 0.0)) fail("error_cost must be >= 0");
  if (refinement_iterations < 0 || refinement_iterations > 100) fail("refinement_iterations must be 0..100");
  if (!(std::isfinite(rebuild_factor) && rebuild_factor > 1.0)) fail("rebuild_factor must be > 1");
  if (min_build_size < 1) fail("min_build_size must be >= 1");
}

EigenspacesIndex::EigenspacesIndex(const EigenspacesOptions& options)
    : options_(options), length_(options.thumbnail.length()) {
  options_.validate();
}

Eigen::VectorXd EigenspacesIndex::thumbnail(size_t slot) const {
  return Eigen::Map<const Eigen::VectorXf>(&thumbnails_[slot * length_], Eigen::Index(length_)).cast<double>();
}

double EigenspacesIndex::residual(size_t slot, size_t space) const {
  return residual_in(spaces_.at(space), thumbnail(slot));
}

void EigenspacesIndex::code_in_best_space(size_t slot, bool may_add_raw) {
  const Eigen::VectorXd x = thumbnail(slot);
  double r = 0.0;
  size_t j = best_space(spaces_, x, &r);
  const double norm2 = 1.0 + options_.thumbnail.depth_weight * options_.thumbnail.depth_weight;
  if (may_add_raw && r >= options_.residual_fraction * norm2) {
    spaces_.push_back(stored(raw_eigenspace(x)));
    j = spaces_.size() - 1;
    r = 0.0;
  }
  Eigen::VectorXd c;
  residual_in(spaces_[j], x, &c);
  Code& code = codes_[slot];
  code.space = std::uint32_t(j);
  code.coefficients.assign(c.data(), c.data() + c.size());
  code.residual = float(r);
}

void EigenspacesIndex::rebuild() {
  const size_t n = codes_.size();
  Thumbnails t{Eigen::Map<const Eigen::MatrixXf>(thumbnails_.data(), Eigen::Index(length_), Eigen::Index(n))
                   .cast<double>()};
  const double norm2 = 1.0 + options_.thumbnail.depth_weight * options_.thumbnail.depth_weight;
  const double theta = options_.residual_fraction * norm2;

  std::vector<Hypothesis> hypotheses;
  for (std::vector<size_t>& seed : make_seeds(t, options_)) hypotheses.push_back(grow(t, std::move(seed), options_, theta));
  std::vector<Space> spaces;
  std::vector<bool> covered(n, false);
  for (size_t h : select_mdl(hypotheses, n, double(length_), norm2, options_.error_cost)) {
    for (size_t m : hypotheses[h].members) covered[m] = true;
    spaces.push_back(std::move(hypotheses[h].space));
  }
  for (size_t i = 0; i < n; ++i)
    if (!covered[i]) spaces.push_back(raw_eigenspace(t.X.col(Eigen::Index(i))));
  for (int it = 0; it < options_.refinement_iterations; ++it) {
    std::vector<std::vector<size_t>> assigned(spaces.size());
    for (size_t i = 0; i < n; ++i) assigned[best_space(spaces, t.X.col(Eigen::Index(i)), nullptr)].push_back(i);
    std::vector<Space> refitted;
    for (size_t j = 0; j < spaces.size(); ++j)
      if (!assigned[j].empty()) refitted.push_back(fit_eigenspace(t, assigned[j], options_.max_dimension, theta));
    spaces = std::move(refitted);
  }
  spaces_.clear();
  for (const Space& sp : spaces) spaces_.push_back(stored(sp));
  for (size_t i = 0; i < n; ++i) code_in_best_space(i, false);
  built_size_ = n;
  ++builds_;
}

void EigenspacesIndex::add(size_t id, const ColorImage& colour, const DepthImage& depth) {
  const std::vector<float> t = make_thumbnail(colour, depth, options_.thumbnail);
  thumbnails_.insert(thumbnails_.end(), t.begin(), t.end());
  codes_.push_back(Code{id, 0, {}, 0.0f});
  const size_t n = codes_.size();
  if (n < size_t(options_.min_build_size) || double(n) >= options_.rebuild_factor * double(built_size_))
    rebuild();
  else
    code_in_best_space(n - 1, true);
}

std::vector<AppearanceMatch> EigenspacesIndex::query(const ColorImage& colour, const DepthImage& depth,
                                                     size_t k) const {
  if (codes_.empty()) return {};
  const std::vector<float> q = make_thumbnail(colour, depth, options_.thumbnail);
  const Eigen::VectorXd x = Eigen::Map<const Eigen::VectorXf>(q.data(), Eigen::Index(q.size())).cast<double>();
  std::vector<Eigen::VectorXd> c_q(spaces_.size());
  std::vector<double> r_q(spaces_.size());
  for (size_t j = 0; j < spaces_.size(); ++j) {
    r_q[j] = residual_in(spaces_[j], x, &c_q[j]);
  }
  std::vector<AppearanceMatch> all(codes_.size());
  for (size_t i = 0; i < codes_.size(); ++i) {
    const Code& c = codes_[i];
    double d2 = r_q[c.space] + double(c.residual);
    for (size_t k2 = 0; k2 < c.coefficients.size(); ++k2) {
      const double e = c_q[c.space](Eigen::Index(k2)) - double(c.coefficients[k2]);
      d2 += e * e;
    }
    all[i] = {c.id, d2};
  }
  return best_matches(std::move(all), k);
}

size_t EigenspacesIndex::bytes_per_keyframe() const {
  if (codes_.empty()) return 0;
  size_t code = 0, model = 0;
  for (const Code& c : codes_) code += c.coefficients.size() * sizeof(float) + sizeof(float) + sizeof(std::uint16_t);
  for (const Eigenspace& s : spaces_) model += size_t(s.basis.cols() + 1) * length_ * sizeof(float);
  return (code + model) / codes_.size();
}

}  // namespace hf::slam
