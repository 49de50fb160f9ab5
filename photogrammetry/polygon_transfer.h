// Transfer of a sketched polygon into a neighbouring shot (Kellner section 5.2, multi-shot mode): instead of
// sketching the polygon again, it is projected into the other shot through a plane hypothesis and positioned to fit
// the same object by matching its edges' colours.
//
//   1. The outline's rays from the source shot meet the hypothesis plane; the points are projected into the target.
//   2. Each outline edge gets a normalised colour histogram of the source image along it (a strip of +-strip_px),
//      each LSD line of the target one of the target image along it, each side of the line separately (a window's
//      bottom edge must not match the top edge of the window below). A line is a candidate for an edge when nearly
//      parallel (max_angle_deg), within search_px of it and overlapping it; its similarity is the histograms'
//      intersection (sum of bin-wise minima, in [0, 1]).
//   3. The best edge-line pair (highest similarity, at least min_similarity; among lines within equal_similarity of
//      an edge's best, the nearest) moves the
//      projected outline across that edge onto its line; the best pair on an edge at least 30 degrees from it moves
//      it along (the translation meeting both offsets). The edges are then snapped to their lines
//      (photogrammetry/edge_snapping.h), or kept where none matches ("approximated if no match was found").
// Repetitive facades (identical windows) give several candidates; search_px bounds the ambiguity, and the user
// picks among the rest in the paper's tool (here the best one is taken).
#pragma once

#include <optional>
#include <vector>

#include "core/image.h"
#include "photogrammetry/edge_snapping.h"
#include "photogrammetry/network.h"

namespace hf::photogrammetry {

struct TransferOptions {
  double search_px = 40.0;
  double max_angle_deg = 10.0;
  double strip_px = 2.0;
  double min_similarity = 0.5;
  double equal_similarity = 0.05;  // lines within this of an edge's best are equal: the nearest wins
  int bins_per_channel = 4;
  SnapOptions snapping;  // the final snap
};

struct TransferResult {
  Polygon2d projected;             // step 1
  Polygon2d points;                // the transferred outline in the target shot
  int anchor_edge = -1;            // the edge of the best pair (-1: none found; points = projected, snapped)
  double anchor_similarity = 0.0;
};

// Normalised RGB histogram (bins_per_channel^3 bins summing to 1; all zero when no pixel is sampled) of the pixels
// within strip_px of the segment a-b: on both sides (side 0), its left (+1: the side of the normal (-u_y, u_x)) or
// its right (-1).
std::vector<double> edge_histogram(const ColorImage& image, const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                   double strip_px, int bins_per_channel, int side = 0);

// nullopt when a ray of the outline misses the plane or a point does not project in front of the target shot.
std::optional<TransferResult> transfer_polygon(const Shot& source, const ColorImage& source_image,
                                               const Polygon2d& outline, const Eigen::Vector4d& plane,
                                               const Shot& target, const ColorImage& target_image,
                                               const std::vector<LineSegment2>& target_lines,
                                               const TransferOptions& options = {});

}  // namespace hf::photogrammetry
