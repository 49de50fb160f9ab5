// Synthetic settlements with an exact answer, for tests and the demo: a hamlet, a village (3 x 3 houses), a
// second hamlet, a town (5 x 5) and a city (7 x 7) in a row on gently sloping ground with scattered trees.
//
// Designed in cells of r = cell_m for one t^S = 2 (the generator's t): a settlement of height h (cells, each
// h = k + 1/4 so t h is never an integer for t in {0.5, 1, 1.5, 2, 3}) spaces its houses G cells apart with
// 2 floor(1.5 h) < G <= 2 floor(2 h), so psi = delta^{t h} joins them at t = 2 and not at t = 1.5 (two discs of
// radius R bridge a gap of G empty cells iff G <= 2 floor(R)); neighbouring settlements a, b are spaced
// floor(2 h_a) + floor(2 h_b) < G_out <= floor(3 h_a) + floor(3 h_b) apart, so they stay apart at t = 2 and merge
// at t = 3. The area thresholds sit between the classes' cluster areas at t = 2 (512, 5676, 23474 and 68544
// cells; every cluster a factor >= 1.4 from every threshold, tests/lidar/test_settlements.cpp), so the truth is
// exact at t = 2 and the sensitivity curve peaks there.
//
// Points: roofs flat at ground + h (building class 6, one or two points per cell, inside the cell), ground class 2
// on every other cell, trees (class 1) above ground. Noise for the building-mask tests: false_positive_cells
// random non-building cells get one stray building point; false_negative_cells random building cells lose their
// building class (to 1), so the mask's TP / FP / FN are known exactly.
#pragma once

#include <cstdint>
#include <vector>

#include "io/las.h"
#include "lidar/differential_profile.h"
#include "lidar/grid.h"

namespace hf::lidar {

struct SyntheticSettlementOptions {
  double cell_m = 1.0;
  std::uint64_t seed = 1;
  int false_positive_cells = 0;
  int false_negative_cells = 0;
};

struct SyntheticSettlements {
  std::vector<LasPoint> points;
  Grid grid;                        // grid_over(points' bounding box, cell_m) equals this
  Image<std::uint8_t> footprints;   // 1 on building cells (before noise): the cadastral truth
  Image<std::uint8_t> classes;      // BuiltUpClass of each building cell at t^S = t_s
  AreaThresholds areas;             // a1 < a2 < a3 separating the classes (m^2)
  double t_s = 2.0;
  int buildings = 0;
  std::int64_t false_positive_cells = 0, false_negative_cells = 0;  // noise actually applied
};

SyntheticSettlements synthetic_settlements(const SyntheticSettlementOptions& options = {});

}  // namespace hf::lidar
