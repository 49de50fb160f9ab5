// `thumbnail`: the plain baseline appearance code. Each keyframe keeps its normalised thumbnail
// (slam/appearance/thumbnails.h: 20x15 intensity + 20x15 depth at weight 0.5, each part zero-mean and
// unit-norm); a query is the
// sum of squared differences to every stored thumbnail (the "tiny image" baseline of Glocker et al. 2015).
// distance in [0, 4 (1 + depth_weight^2)]. Query cost O(size() * length), memory length * 4 bytes per keyframe.
#pragma once

#include "slam/appearance.h"
#include "slam/appearance/thumbnails.h"

namespace hf::slam {

struct ThumbnailIndexOptions {
  // 20x15 cells, depth part weighted 0.5: the best of the grid on the tuning part (bench/results/
  // appearance.tuning.md; 1.0 ties on p@1, 0.5 leads p@5 by a hair).
  ThumbnailOptions thumbnail{20, 15, 0.5};
};

class ThumbnailIndex : public AppearanceIndex {
 public:
  explicit ThumbnailIndex(const ThumbnailIndexOptions& options = {});  // hf::Error for bad options
  std::string name() const override { return "thumbnail"; }
  void add(size_t id, const ColorImage& colour, const DepthImage& depth) override;
  std::vector<AppearanceMatch> query(const ColorImage& colour, const DepthImage& depth, size_t k) const override;
  size_t size() const override { return ids_.size(); }
  size_t bytes_per_keyframe() const override { return options_.thumbnail.length() * sizeof(float); }

 private:
  ThumbnailIndexOptions options_;
  std::vector<size_t> ids_;
  std::vector<float> thumbnails_;  // size() rows of length()
};

}  // namespace hf::slam
