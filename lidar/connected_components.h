// Connected components C_i of a binary raster under 8-connectivity (the connectivity opening Gamma_{s_i} of
// Cvirn eq. 1 for every s_i at once), with the attributes the filters need.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"

namespace hf::lidar {

using Mask = Image<std::uint8_t>;  // 1 = in the set, 0 = not

struct Components {
  Image<std::int32_t> label;  // -1 outside the set, else 0..count-1 in raster order of first cell (deterministic)
  int count = 0;
  std::vector<std::int64_t> cells;                 // A(C_i) in cells
  std::vector<int> min_col, min_row, max_col, max_row;  // bounding box of each component (cells, inclusive)
};

// Labels the 8-connected components of `mask` (nonzero = in the set).
Components connected_components(const Mask& mask);

}  // namespace hf::lidar
