// Height of each building component above local ground: h(g_i) of Cvirn eq. 6, the supremum of its points'
// heights, where a point's height is measured from the ground around the building rather than from the datum
// (an absolute z would make a hilltop hamlet "taller" than a city in a valley).
//
// Local ground of a component C: the mean elevation of the ground-class points in the cells of C's bounding
// box grown by ground_margin_m on every side (clipped to the grid). A box rather than a ring around C keeps the
// query O(1) (summed-area tables) and local, so a tile needs only that margin of halo. When the box holds no
// ground point (a component wider than the survey's ground, or data without a ground class) the lowest point of
// any class in the box stands in for it. h(C) = max building z in C - ground(C), clamped at 0 (never NaN).
#pragma once

#include <vector>

#include "lidar/connected_components.h"
#include "lidar/grid.h"

namespace hf::lidar {

struct HeightOptions {
  double ground_margin_m = 10.0;  // wide enough to reach the street around a building; measured in bench/results/lidar.md
};

// Heights (metres) of every component of `buildings` (labelled on raster.building).
std::vector<double> building_heights(const CellRaster& raster, const Components& buildings, const HeightOptions& options = {});

// The per-cell height function of eq. 6: h(g) = h(C) for g in C, 0 elsewhere.
Image<float> height_raster(const Components& buildings, const std::vector<double>& heights);

}  // namespace hf::lidar
