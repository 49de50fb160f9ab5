#include "lidar/connected_components.h"

#include <algorithm>

namespace hf::lidar {

Components connected_components(const Mask& mask) {
  const int w = mask.width(), h = mask.height();
  Components c;
  c.label = Image<std::int32_t>(w, h, -1);
  // Flood fill with an explicit stack: components can be millions of cells, too deep for recursion.
  std::vector<std::int64_t> stack;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      if (!mask(x, y) || c.label(x, y) >= 0) continue;
      const int id = c.count++;
      c.cells.push_back(0);
      c.min_col.push_back(x), c.max_col.push_back(x), c.min_row.push_back(y), c.max_row.push_back(y);
      c.label(x, y) = id;
      stack.push_back(std::int64_t(y) * w + x);
      while (!stack.empty()) {
        const std::int64_t at = stack.back();
        stack.pop_back();
        const int cx = static_cast<int>(at % w), cy = static_cast<int>(at / w);
        ++c.cells[id];
        c.min_col[id] = std::min(c.min_col[id], cx), c.max_col[id] = std::max(c.max_col[id], cx);
        c.min_row[id] = std::min(c.min_row[id], cy), c.max_row[id] = std::max(c.max_row[id], cy);
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx) {
            const int nx = cx + dx, ny = cy + dy;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h || !mask(nx, ny) || c.label(nx, ny) >= 0) continue;
            c.label(nx, ny) = id;
            stack.push_back(std::int64_t(ny) * w + nx);
          }
      }
    }
  return c;
}

}  // namespace hf::lidar
