#include "fusion/sparse_render.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/kernels/image_kernels.h"
#include "core/mesh_interpolation.h"
#include "core/parallel.h"
#include "fusion/raycast_sampled.h"
#include "core/timing.h"

namespace hf::fusion {
namespace {

Rgb8 to_rgb8(const float* v) {
  auto c = [](float x) { return std::uint8_t(x <= 0.0f ? 0 : (x >= 255.0f ? 255 : int(x + 0.5f))); };
  return Rgb8{c(v[0]), c(v[1]), c(v[2])};
}

}  // namespace

SparseRender render_masked(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                           RaycastOptions options, const Image<std::uint8_t>& rays, Reconstruction method) {
  options.shade = true;
  SparseRender out;
  auto t0 = std::chrono::steady_clock::now();
  RaycastResult cast;
  raycast_sampled(grid, camera, T_world_camera, options, rays, &cast);
  out.cast_ms = ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  const size_t n = size_t(camera.width) * camera.height;
  std::vector<float> values(n * 3);
  std::vector<std::uint8_t> mask(n);
  for (size_t i = 0; i < n; ++i) {
    const Rgb8 c = cast.shaded.pixels()[i];
    values[3 * i] = c.r, values[3 * i + 1] = c.g, values[3 * i + 2] = c.b;
    mask[i] = rays.pixels()[i] != 0 ? 1 : 0;
    out.rays += mask[i];
  }
  if (method == Reconstruction::push_pull) {
    out.fill = push_pull_fill(camera.width, camera.height, 3, values.data(), mask.data());
  } else {
    out.fill = mesh_interpolate(camera.width, camera.height, 3, values.data(), mask.data()).fill;
  }
  out.shaded = ColorImage(camera.width, camera.height);
  for (size_t i = 0; i < n; ++i) out.shaded.pixels()[i] = to_rgb8(&values[3 * i]);
  out.reconstruct_ms = ms_since(t0);
  return out;
}

SparseRender render_focus_context(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                                  RaycastOptions options, const PixelRect& roi, int context_level) {
  if (context_level < 1 || context_level > 4)
    throw Error("render_focus_context: context_level must be in [1, 4], got " + std::to_string(context_level));
  if (!(roi.x0 >= 0 && roi.y0 >= 0 && roi.x1 <= camera.width && roi.y1 <= camera.height && roi.x0 < roi.x1 &&
        roi.y0 < roi.y1))
    throw Error("render_focus_context: region [" + std::to_string(roi.x0) + ", " + std::to_string(roi.x1) + ") x [" +
                std::to_string(roi.y0) + ", " + std::to_string(roi.y1) + ") is empty or outside " + camera.describe());
  options.shade = true;
  options.depth_hint = nullptr;  // a hint is the full camera's size; neither cast here has it
  SparseRender out;
  auto t0 = std::chrono::steady_clock::now();
  const PinholeCamera context = camera.scaled(context_level);
  PinholeCamera focus = camera;
  focus.cx -= roi.x0, focus.cy -= roi.y0;
  focus.width = roi.x1 - roi.x0, focus.height = roi.y1 - roi.y0;
  const RaycastResult low = raycast(grid, context, T_world_camera, options);
  const RaycastResult high = raycast(grid, focus, T_world_camera, options);
  out.rays = long(context.width) * context.height + long(focus.width) * focus.height;
  out.cast_ms = ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  // The context's grey channel resampled at every pixel centre: level-l coordinates (x + 0.5) / 2^l - 0.5.
  Image<float> grey(context.width, context.height);
  for (size_t i = 0; i < grey.size(); ++i) grey.pixels()[i] = low.shaded.pixels()[i].r;
  out.shaded = ColorImage(camera.width, camera.height);
  const float s = 1.0f / float(1 << context_level);
  parallel_for_rows(camera.height, [&](int y) {
    for (int x = 0; x < camera.width; ++x) {
      if (x >= roi.x0 && x < roi.x1 && y >= roi.y0 && y < roi.y1) {
        out.shaded(x, y) = high.shaded(x - roi.x0, y - roi.y0);
        continue;
      }
      float v = 0.0f;
      const float u = std::min(std::max((x + 0.5f) * s - 0.5f, 0.0f), float(context.width - 1));
      const float w = std::min(std::max((y + 0.5f) * s - 0.5f, 0.0f), float(context.height - 1));
      hf_sample_bilinear(grey.data(), grey.width(), grey.height(), u, w, 0, &v);
      const float rgb[3] = {v, v, v};
      out.shaded(x, y) = to_rgb8(rgb);
    }
  });
  out.reconstruct_ms = ms_since(t0);
  return out;
}

SparseRender render_conus(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                          RaycastOptions options, const SamplingMap& map) {
  if (map.width() != camera.width || map.height() != camera.height)
    throw Error("render_conus: the sampling map is for " + std::to_string(map.width()) + "x" +
                std::to_string(map.height()) + " images but the camera is " + camera.describe());
  options.shade = true;
  SparseRender out;
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<MapPoint> rays = map.rays();
  auto pixel_of = [&](const MapPoint& p) {
    const int x = std::clamp(int(std::lround(p.u)), 0, camera.width - 1);
    const int y = std::clamp(int(std::lround(p.v)), 0, camera.height - 1);
    return size_t(y) * camera.width + x;
  };
  Image<std::uint8_t> mask(camera.width, camera.height, 0);
  for (const MapPoint& p : rays) mask.pixels()[pixel_of(p)] = 1;
  RaycastResult cast;
  raycast_sampled(grid, camera, T_world_camera, options, mask, &cast);
  for (std::uint8_t m : mask.pixels()) out.rays += m;
  out.cast_ms = ms_since(t0);

  t0 = std::chrono::steady_clock::now();
  out.conus = Image<float>(map.conus_width(), map.conus_height());
  for (size_t i = 0; i < rays.size(); ++i) out.conus.pixels()[i] = cast.shaded.pixels()[pixel_of(rays[i])].r;
  const Image<float> uniform = from_conus(out.conus, map);
  out.shaded = ColorImage(camera.width, camera.height);
  for (size_t i = 0; i < uniform.size(); ++i) {
    const float v = uniform.pixels()[i];
    const float rgb[3] = {v, v, v};
    out.shaded.pixels()[i] = to_rgb8(rgb);
  }
  out.reconstruct_ms = ms_since(t0);
  return out;
}

}  // namespace hf::fusion
