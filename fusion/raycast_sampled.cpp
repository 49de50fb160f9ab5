#include "fusion/raycast_sampled.h"

#include <algorithm>
#include <string>
#include <vector>

#include "core/error.h"
#include "fusion/raycast_stages.h"

namespace hf::fusion {

void raycast_sampled(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                     const RaycastOptions& options, const Image<std::uint8_t>& rays, RaycastResult* out) {
  raycast_pixels(grid, camera, T_world_camera, options, &rays, out);
}

Image<std::uint8_t> dilate_rays(const Image<std::uint8_t>& rays, int radius_px) {
  if (radius_px < 0) throw Error("dilate_rays: radius_px must be >= 0, got " + std::to_string(radius_px));
  const int W = rays.width(), H = rays.height();
  // Separable: a running window along x, then along y.
  Image<std::uint8_t> row(W, H, 0), out(W, H, 0);
  for (int y = 0; y < H; ++y) {
    int last = -1 - radius_px;  // the last set pixel to the left, within reach
    std::vector<int> next(size_t(W) + 1, W + radius_px + 1);
    for (int x = W - 1; x >= 0; --x) next[size_t(x)] = rays(x, y) != 0 ? x : next[size_t(x) + 1];
    for (int x = 0; x < W; ++x) {
      if (rays(x, y) != 0) last = x;
      row(x, y) = (x - last <= radius_px || next[size_t(x)] - x <= radius_px) ? 1 : 0;
    }
  }
  for (int x = 0; x < W; ++x) {
    int last = -1 - radius_px;
    std::vector<int> next(size_t(H) + 1, H + radius_px + 1);
    for (int y = H - 1; y >= 0; --y) next[size_t(y)] = row(x, y) != 0 ? y : next[size_t(y) + 1];
    for (int y = 0; y < H; ++y) {
      if (row(x, y) != 0) last = y;
      out(x, y) = (y - last <= radius_px || next[size_t(y)] - y <= radius_px) ? 1 : 0;
    }
  }
  return out;
}

}  // namespace hf::fusion
