#include "core/normals.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
#include "core/kernels/image_kernels.h"

namespace hf {
VertexMap compute_vertex_map(const DepthImage& depth, const PinholeCamera& camera) {
  if (camera.width != depth.width() || camera.height != depth.height()) {
    throw Error("compute_vertex_map: camera is " + std::to_string(camera.width) + "x" + std::to_string(camera.height) +
                " but the depth image is " + std::to_string(depth.width()) + "x" + std::to_string(depth.height()) +
                " (use camera.scaled(level) for pyramid levels)");
  }
  VertexMap out(depth.width(), depth.height());
  const hf_intrinsics K = camera.kernel_intrinsics();
  const float* src = depth.data();
  hf_float4* dst = out.data();
  const int w = depth.width();
  parallel_for_rows(depth.height(), [&](int y) {
    for (int x = 0; x < w; ++x) dst[size_t(y) * w + x] = hf_vertex_pixel(src, K, x, y);
  });
  return out;
}

NormalMap compute_normal_map(const VertexMap& vertices, const NormalParams& p) {
  if (!(std::isfinite(p.max_depth_jump_ratio) && p.max_depth_jump_ratio > 0.0f)) {
    throw Error("compute_normal_map: expected a finite max_depth_jump_ratio > 0, got " +
                std::to_string(p.max_depth_jump_ratio));
  }
  NormalMap out(vertices.width(), vertices.height());
  const hf_float4* src = vertices.data();
  hf_float4* dst = out.data();
  const int w = vertices.width(), h = vertices.height();
  const float ratio = p.max_depth_jump_ratio;
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) dst[size_t(y) * w + x] = hf_normal_pixel(src, w, h, x, y, ratio);
  });
  return out;
}

}  // namespace hf
