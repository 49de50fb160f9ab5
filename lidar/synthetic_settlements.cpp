#include "lidar/synthetic_settlements.h"

#include <algorithm>
#include <cmath>
#include <random>

#include "core/error.h"

namespace hf::lidar {
namespace {

struct Settlement {
  int houses_per_side;  // n x n houses
  int house_cells;      // side of a square house
  int height_k;         // height = k + 1/4 cells
  BuiltUpClass truth;
};

// Gap inside a settlement: strictly above 2 floor(1.5 h) (not bridged at t = 1.5), at most 2 floor(2 h).
int inner_gap(double h) { return static_cast<int>(std::floor(1.5 * h) + std::floor(2.0 * h)); }
// Gap between settlements: above floor(2 h_a) + floor(2 h_b), at most floor(3 h_a) + floor(3 h_b).
int outer_gap(double ha, double hb) {
  const double lo = std::floor(2 * ha) + std::floor(2 * hb), hi = std::floor(3 * ha) + std::floor(3 * hb);
  return static_cast<int>(std::floor((lo + hi) / 2)) + 1;
}

}  // namespace

SyntheticSettlements synthetic_settlements(const SyntheticSettlementOptions& o) {
  if (!(o.cell_m > 0 && std::isfinite(o.cell_m))) throw Error("synthetic settlements: cell size must be positive");
  const double r = o.cell_m;
  const std::vector<Settlement> layout = {{1, 8, 4, BuiltUpClass::hamlet},
                                          {3, 8, 5, BuiltUpClass::village},
                                          {1, 8, 4, BuiltUpClass::hamlet},
                                          {5, 10, 6, BuiltUpClass::town},
                                          {7, 10, 8, BuiltUpClass::city}};
  const int margin = 30;  // cells of bare ground around the scene (more than the ground margin of the heights)
  std::vector<int> extent, start;
  int x = margin, tallest = 0;
  for (size_t i = 0; i < layout.size(); ++i) {
    const Settlement& s = layout[i];
    const double h = s.height_k + 0.25;
    if (i > 0) x += outer_gap(layout[i - 1].height_k + 0.25, h);
    extent.push_back(s.houses_per_side * s.house_cells + (s.houses_per_side - 1) * inner_gap(h));
    start.push_back(x);
    x += extent.back();
    tallest = std::max(tallest, extent.back());
  }
  SyntheticSettlements out;
  out.grid = Grid{r, 0, tallest + 2 * margin, x + margin, tallest + 2 * margin};
  const int w = out.grid.width, hgt = out.grid.height;
  out.footprints = Image<std::uint8_t>(w, hgt, 0);
  out.classes = Image<std::uint8_t>(w, hgt, 0);
  // Thresholds between the classes' cluster areas at t = 2 (512, 5676, 23474, 68544 cells), scaled to m^2.
  out.areas = AreaThresholds{1500 * r * r, 10000 * r * r, 35000 * r * r};
  std::vector<float> roof(size_t(w) * hgt, 0.0f);  // height above ground per building cell (metres)

  for (size_t i = 0; i < layout.size(); ++i) {
    const Settlement& s = layout[i];
    const double h = s.height_k + 0.25;
    const int gap = inner_gap(h);
    const int y0 = margin + (tallest - extent[i]) / 2;
    for (int a = 0; a < s.houses_per_side; ++a)
      for (int b = 0; b < s.houses_per_side; ++b) {
        ++out.buildings;
        const int cx = start[i] + a * (s.house_cells + gap), cy = y0 + b * (s.house_cells + gap);
        for (int yy = cy; yy < cy + s.house_cells; ++yy)
          for (int xx = cx; xx < cx + s.house_cells; ++xx) {
            out.footprints(xx, yy) = 1;
            out.classes(xx, yy) = static_cast<std::uint8_t>(s.truth);
            roof[size_t(yy) * w + xx] = static_cast<float>(h * r);
          }
      }
  }

  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> jitter(-0.3, 0.3), unit(0, 1);
  std::normal_distribution<double> ground_noise(0, 0.02);
  // Ground: a gentle plane (0.2 % east, 0.1 % north), so heights must be measured from local ground.
  const auto ground_z = [&](double px, double py) { return 2.0 + 0.002 * px + 0.001 * py; };
  const auto centre = [&](int col, int row, double& px, double& py) {
    px = (col + 0.5) * r;
    py = (out.grid.row0 - 1 - row + 0.5) * r;
  };
  const auto emit = [&](int col, int row, double z, int cls) {
    LasPoint p;
    centre(col, row, p.x, p.y);
    p.x += jitter(rng) * r, p.y += jitter(rng) * r;
    p.z = z;
    p.classification = static_cast<std::uint8_t>(cls);
    p.return_number = p.number_of_returns = 1;
    out.points.push_back(p);
  };

  // Noise cells, chosen first so that the rest of the scene is the same for every noise level.
  std::vector<char> flip_to_building(size_t(w) * hgt, 0), flip_to_other(size_t(w) * hgt, 0);
  std::mt19937_64 noise_rng(o.seed ^ 0x9e3779b97f4a7c15ull);
  std::uniform_int_distribution<int> any_col(0, w - 1), any_row(0, hgt - 1);
  const auto near_building = [&](int c, int rr) {
    for (int dy = -2; dy <= 2; ++dy)
      for (int dx = -2; dx <= 2; ++dx) {
        const int xx = c + dx, yy = rr + dy;
        if (xx >= 0 && yy >= 0 && xx < w && yy < hgt && out.footprints(xx, yy)) return true;
      }
    return false;
  };
  for (int n = 0, tries = 0; n < o.false_positive_cells && tries < 1000000; ++tries) {
    const int c = any_col(noise_rng), rr = any_row(noise_rng);
    if (near_building(c, rr) || flip_to_building[size_t(rr) * w + c]) continue;
    flip_to_building[size_t(rr) * w + c] = 1, ++n, ++out.false_positive_cells;
  }
  for (int n = 0, tries = 0; n < o.false_negative_cells && tries < 1000000; ++tries) {
    const int c = any_col(noise_rng), rr = any_row(noise_rng);
    if (!out.footprints(c, rr) || flip_to_other[size_t(rr) * w + c]) continue;
    flip_to_other[size_t(rr) * w + c] = 1, ++n, ++out.false_negative_cells;
  }

  for (int row = 0; row < hgt; ++row)
    for (int col = 0; col < w; ++col) {
      double px, py;
      centre(col, row, px, py);
      const double g = ground_z(px, py);
      const size_t at = size_t(row) * w + col;
      const bool corner = (col == 0 || col == w - 1) && (row == 0 || row == hgt - 1);
      if (out.footprints(col, row)) {
        const int cls = flip_to_other[at] ? 1 : 6;
        const double roof_z = g + roof[at];
        emit(col, row, roof_z, cls);
        if (unit(rng) < 0.5) emit(col, row, roof_z, cls);
        continue;
      }
      if (corner || (col % 2 == 0 && row % 2 == 0)) emit(col, row, g + ground_noise(rng), 2);
      if (flip_to_building[at]) emit(col, row, g + 3.0, 6);
      else if (!near_building(col, row) && unit(rng) < 0.01) emit(col, row, g + 2.0 + 10.0 * unit(rng), 1);  // a tree
    }
  return out;
}

}  // namespace hf::lidar
