// The clustering operator psi of Cvirn section 4.1: the spatially variant dilation delta^{t^S h}, after
// Bouaynaya et al. A cell s of S dilates by the disc of radius R(s) = t^S h(s) metres (h of eq. 6: the height of
// s's building), so tall buildings reach farther: delta(S) = { x | exists s in S: |x - s| <= R(s) }, distances
// between cell centres. Extensive (R >= 0 keeps s) and increasing (a superset stamps a superset of discs).
//
// Cost: only cells whose disc is not already covered are stamped: s needs no stamp when its four 4-neighbours
// are in S with radii >= R(s), because any x in s's disc other than s is strictly nearer to one of them (the
// axis neighbour n closest to the direction of x - s has (x - s).n >= |x - s| / sqrt 2 >= 1/2 for |x - s| >= 1).
// Each stamp adds its disc row by row into a difference array: O(boundary cells x radius), exact.
#pragma once

#include "core/image.h"
#include "lidar/connected_components.h"

namespace hf::lidar {

// delta(S) for per-cell radii in cells (radius_cells(x, y) is read where mask is set; negative means 0).
Mask variant_dilation(const Mask& mask, const Image<float>& radius_cells);

// The radii R = t^S h / r of the clustering operator for heights in metres on cells of cell_m.
Image<float> clustering_radii(const Image<float>& height_m, double t_s, double cell_m);

}  // namespace hf::lidar
