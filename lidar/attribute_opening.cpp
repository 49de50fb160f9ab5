#include "lidar/attribute_opening.h"

#include "core/error.h"

namespace hf::lidar {

Mask area_opening(const Mask& x, double a_m2, double cell_m) {
  const Components c = connected_components(x);
  Mask out(x.width(), x.height(), 0);
  const double cell_area = cell_m * cell_m;
  for (size_t i = 0; i < out.size(); ++i)
    if (const int id = c.label.pixels()[i]; id >= 0 && double(c.cells[id]) * cell_area >= a_m2) out.pixels()[i] = 1;
  return out;
}

Mask second_generation_opening(const Mask& s, const Mask& psi_s, double a_m2, double cell_m) {
  if (s.width() != psi_s.width() || s.height() != psi_s.height()) throw Error("second_generation_opening: psi(S) size differs from S");
  Mask out = area_opening(psi_s, a_m2, cell_m);
  for (size_t i = 0; i < out.size(); ++i) out.pixels()[i] = out.pixels()[i] && s.pixels()[i];
  return out;
}

}  // namespace hf::lidar
