// `eigenspaces`: the multiple-eigenspaces appearance code (Leonardis, Bischof & Maver, "Multiple eigenspaces",
// Pattern Recognition 35(11) 2002, as used by Grabner et al., ../shared/seeds/002_*.txt section 2.1):
//   x_i ~ mu_j + sum_{k=1..d_j} c_jk^(i) e_jk   for the one eigenspace j with I_j^(i) = 1.
//
// Build (from the normalised thumbnails x_i of all keyframes, slam/appearance/thumbnails.h):
//   1. seeds: up to max_seeds keyframes spread evenly over the index, each with its seed_size - 1 nearest
//      thumbnails (squared distance);
//   2. eigenspace growing, from every seed independently: fit the PCA eigenspace of the members (mean, and the
//      smallest dimension d <= max_dimension at which every member's squared residual is below theta), then add
//      the non-members whose residual ||x - mu - E E^T (x - mu)||^2 is below theta, at most max(1, members / 4) of
//      them per step, smallest first, until none qualifies;
//   3. eigenspace selection by minimum description length (greedy form of Leonardis' selection): each hypothesis
//      saves, over the images it would newly cover, sum_i (D - d - error_cost * D * r_i / |x|^2) numbers against
//      storing them raw, minus its model (d + 1) * D; the largest positive saving is taken and its images marked
//      covered, until no saving is positive; a keyframe no selected eigenspace covers is kept raw, as MDL prefers
//      for an image no eigenspace explains: a 0-dimensional eigenspace whose mean is its thumbnail;
//   4. each keyframe is assigned to the selected eigenspace that reconstructs it best (smallest residual), every
//      eigenspace is refitted to its keyframes (refinement_iterations times), and the final assignment is made
//      once more by that rule: a keyframe's code is its coefficients c = E_j^T (x - mu_j) and residual r in the
//      eigenspace j that reconstructs it best among the final ones.
// theta = residual_fraction * (1 + depth_weight^2) (the squared norm of a thumbnail with both parts).
//
// Query: the query thumbnail is coded in every eigenspace j (c_q^j, r_q^j) and keyframe i of eigenspace j is at
//   distance ||c_q^j - c_i||^2 + r_q^j + r_i,
// the squared thumbnail distance with the two residuals taken as orthogonal to each other (exact when either
// residual is zero). Cost: one projection per eigenspace (D * d each) plus d per keyframe.
//
// Incremental rule: the eigenspaces are rebuilt from all thumbnails when size() reaches rebuild_factor times the
// size at the last build (and on every add below min_build_size keyframes); in between, a new keyframe is coded
// in the existing eigenspace that reconstructs it best, or kept raw (a new 0-dimensional eigenspace) when even
// that one leaves a residual >= theta. Rebuild cost O(seeds * steps * (N D d + M^2 D)) for N
// keyframes and members M; with geometric growth the amortised cost per add is a constant factor
// (1 / (1 - 1 / rebuild_factor) = 3 for 1.5) times one rebuild's share. The rebuilds need the thumbnails: they are
// kept (rebuild_bytes_per_keyframe(), not part of bytes_per_keyframe(), which is the code and model retrieval uses).
// Deterministic: no randomness; ties go to the smaller index.
// Measured (bench/results/appearance.md, report cases): p@1 0.722 / p@5 0.652 against the thumbnail's 0.729 / 0.652
// from 1758 B per keyframe instead of 2400 (plus the 2400 B rebuild store): keyframes 5 cm / 5 degrees apart are
// correlated enough for some to share eigenspaces, and the rest stay raw.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "slam/appearance.h"
#include "slam/appearance/thumbnails.h"

namespace hf::slam {

struct EigenspacesOptions {
  ThumbnailOptions thumbnail{};   // 20x15, depth weight 1 (the tuning grid: appearance.tuning.md)
  int max_dimension = 3;            // d_max; Grabner et al. use 3 (mean + 3 eigenimages per render pass)
  double residual_fraction = 0.1;   // theta over a thumbnail's squared norm; chosen in appearance.tuning.md
  int seed_size = 3;                // images per seed
  int max_seeds = 64;               // hypotheses grown per build
  double error_cost = 1.0;          // weight of the residual in the MDL saving
  int refinement_iterations = 2;    // refits after the selection
  double rebuild_factor = 1.5;      // rebuild when the index has grown by this factor
  int min_build_size = 8;           // below this many keyframes, rebuild on every add
  void validate() const;            // hf::Error naming the bad field
};

class EigenspacesIndex : public AppearanceIndex {
 public:
  explicit EigenspacesIndex(const EigenspacesOptions& options = {});  // hf::Error for bad options
  std::string name() const override { return "eigenspaces"; }
  void add(size_t id, const ColorImage& colour, const DepthImage& depth) override;
  std::vector<AppearanceMatch> query(const ColorImage& colour, const DepthImage& depth, size_t k) const override;
  size_t size() const override { return codes_.size(); }
  size_t bytes_per_keyframe() const override;
  size_t rebuild_bytes_per_keyframe() const { return options_.thumbnail.length() * sizeof(float); }

  // Introspection (tests, reports). `slot` is the position in order of addition.
  size_t eigenspace_count() const { return spaces_.size(); }
  int dimension(size_t space) const { return int(spaces_.at(space).basis.cols()); }
  size_t eigenspace_of(size_t slot) const { return codes_.at(slot).space; }
  // Squared residual of keyframe `slot`'s thumbnail in eigenspace `space`.
  double residual(size_t slot, size_t space) const;
  // The stored code's residual (equal to residual(slot, eigenspace_of(slot)) right after a build).
  double code_residual(size_t slot) const { return codes_.at(slot).residual; }
  size_t builds() const { return builds_; }

  // Built in double, kept in float (what bytes_per_keyframe counts); codes and queries compute in double.
  struct Eigenspace {
    Eigen::VectorXf mean;   // D
    Eigen::MatrixXf basis;  // D x d, orthonormal columns, by decreasing eigenvalue
  };

 private:
  struct Code {
    size_t id = 0;
    std::uint32_t space = 0;
    std::vector<float> coefficients;  // d of `space`
    float residual = 0.0f;
  };
  Eigen::VectorXd thumbnail(size_t slot) const;
  void rebuild();
  void code_in_best_space(size_t slot, bool may_add_raw);

  EigenspacesOptions options_;
  size_t length_ = 0;           // D
  std::vector<float> thumbnails_;  // rebuild store: size() rows of D
  std::vector<Code> codes_;
  std::vector<Eigenspace> spaces_;
  size_t built_size_ = 0, builds_ = 0;
};

}  // namespace hf::slam
