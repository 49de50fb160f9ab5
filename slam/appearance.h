// Appearance codes for keyframe retrieval (relocalisation and loop-closure candidates): a compact code per keyframe
// and a query that ranks the stored keyframes by how similar they look to a new frame.
//
//   std::unique_ptr<AppearanceIndex> index = make_appearance_index(default_appearance_index_name());
//   index->add(keyframe_id, colour, depth);
//   std::vector<AppearanceMatch> best = index->query(colour, depth, 5);  // ascending distance
//
// Methods (one file pair each under slam/appearance/, options in their headers):
//   eigenspaces  multiple eigenspaces (Leonardis, Bischof & Maver 2002, as used by Grabner et al.): normalised
//                thumbnails grouped by eigenspace growing + MDL selection, one PCA eigenspace per group, each
//                keyframe coded by its coefficients in the eigenspace that reconstructs it best.
//   ferns        random ferns (Glocker et al. 2015, as in InfiniTAM / ElasticFusion): RGB-D binary tests on an
//                80x60 frame, block-wise Hamming distance.
//   thumbnail    the baseline: sum of squared differences of normalised 20x15 intensity + depth thumbnails.
// The default, ferns, is the winner of the retrieval measurement in bench/results/appearance.md (mean p@1, then
// p@5, over the untouched sequences; the numbers are in appearance.cpp beside default_appearance_index_name()).
//
// Images: colour RGB8, depth metres with 0 = no measurement, both the same size (any size >= the method's code
// size is accepted; smaller or mismatched images are still coded, never rejected). Colour may be empty: the
// methods then code depth alone. Bad pixels (NaN / inf / zero depth, black or saturated colour) never throw and
// never make a distance NaN: every distance a query returns is finite.
// Thread-safety: query() and the const accessors may run concurrently; add() needs exclusive access.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"

namespace hf::slam {

struct AppearanceMatch {
  size_t id = 0;          // the id the keyframe was added with
  double distance = 0.0;  // method-specific dissimilarity, >= 0, smaller = more similar; finite
};

class AppearanceIndex {
 public:
  virtual ~AppearanceIndex() = default;
  virtual std::string name() const = 0;
  // Adds a keyframe. Ids are the caller's (need not be dense or sorted); adding an id twice stores two codes.
  virtual void add(size_t id, const ColorImage& colour, const DepthImage& depth) = 0;
  // The min(k, size()) most similar keyframes, sorted by ascending distance (ties: the earlier added first).
  // An empty index returns an empty vector.
  virtual std::vector<AppearanceMatch> query(const ColorImage& colour, const DepthImage& depth, size_t k) const = 0;
  virtual size_t size() const = 0;
  // Bytes of one keyframe's code plus its share (1 / size()) of the method's shared model (eigenimages, fern
  // thresholds); what retrieval needs in memory, not the bookkeeping of std containers.
  virtual size_t bytes_per_keyframe() const = 0;
};

// For implementations: the k smallest of `candidates` (given in order of addition), sorted by ascending distance,
// ties kept in that order.
std::vector<AppearanceMatch> best_matches(std::vector<AppearanceMatch> candidates, size_t k);

// Throws hf::Error "unknown appearance index 'X' (known: eigenspaces, ferns, thumbnail)".
std::unique_ptr<AppearanceIndex> make_appearance_index(const std::string& name);
std::vector<std::string> appearance_index_names();  // sorted
// The method bench/results/appearance.md measured best (see the table there and the pointer in appearance.cpp).
std::string default_appearance_index_name();

}  // namespace hf::slam
