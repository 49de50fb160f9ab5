#include "slam/appearance/thumbnail.h"

namespace hf::slam {

ThumbnailIndex::ThumbnailIndex(const ThumbnailIndexOptions& options) : options_(options) {
  options_.thumbnail.validate();
}

void ThumbnailIndex::add(size_t id, const ColorImage& colour, const DepthImage& depth) {
  const std::vector<float> t = make_thumbnail(colour, depth, options_.thumbnail);
  thumbnails_.insert(thumbnails_.end(), t.begin(), t.end());
  ids_.push_back(id);
}

std::vector<AppearanceMatch> ThumbnailIndex::query(const ColorImage& colour, const DepthImage& depth,
                                                   size_t k) const {
  const std::vector<float> q = make_thumbnail(colour, depth, options_.thumbnail);
  const size_t n = q.size();
  std::vector<AppearanceMatch> all(ids_.size());
  for (size_t i = 0; i < ids_.size(); ++i) all[i] = {ids_[i], squared_distance(q.data(), &thumbnails_[i * n], n)};
  return best_matches(std::move(all), k);
}

}  // namespace hf::slam
