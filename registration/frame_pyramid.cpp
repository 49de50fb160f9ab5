#include "registration/frame_pyramid.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/filters.h"
#include "core/kernels/image_kernels.h"
#include "core/normals.h"
#include "core/push_pull.h"
#include "core/pyramid.h"

namespace hf {
namespace {

void check_size(int width, int height, const PinholeCamera& camera, const char* what) {
  if (width != camera.width || height != camera.height) {
    throw Error(std::string("frame pyramid: ") + what + " is " + std::to_string(width) + "x" +
                std::to_string(height) + " but the camera is " + std::to_string(camera.width) + "x" +
                std::to_string(camera.height));
  }
}

void add_intensity(FramePyramid& pyramid, const IntensityImage& level0) {
  const std::vector<Image<float>> intensity = build_gaussian_pyramid(level0, pyramid.num_levels());
  for (int l = 0; l < pyramid.num_levels(); ++l) {
    FramePyramidLevel& level = pyramid.levels[size_t(l)];
    level.intensity = intensity[size_t(l)];
    ImageGradients g = image_gradients(level.intensity);
    level.grad_x = std::move(g.dx);
    level.grad_y = std::move(g.dy);
  }
}

}  // namespace

FramePyramid build_frame_pyramid(const DepthImage& depth, const ColorImage* color, const PinholeCamera& camera,
                                 const FramePyramidOptions& options) {
  if (options.levels < 1) throw Error("frame pyramid: levels must be >= 1, got " + std::to_string(options.levels));
  if (options.first_level < 0 || options.first_level > 4)
    throw Error("frame pyramid: first_level must be in [0, 4], got " + std::to_string(options.first_level));
  if (options.fill_holes_levels < 0 || options.fill_holes_levels > 8)
    throw Error("frame pyramid: fill_holes_levels must be in [0, 8], got " + std::to_string(options.fill_holes_levels));
  check_size(depth.width(), depth.height(), camera, "the depth image");
  if (color != nullptr) check_size(color->width(), color->height(), camera, "the colour image");

  DepthImage d = depth;
  for (float& z : d.pixels()) {
    const bool keep = std::isfinite(z) && z > 0.0f && z >= options.min_depth_m &&
                      (options.max_depth_m <= 0.0f || z <= options.max_depth_m);
    if (!keep) z = 0.0f;
  }
  for (int l = 0; l < options.first_level; ++l) d = pyr_down_depth(d);
  if (options.fill_holes_levels > 0) push_pull_fill_depth(d, PushPullOptions{options.fill_holes_levels});
  if (options.bilateral_filter) d = bilateral_filter_depth(d);
  const std::vector<DepthImage> depths = build_depth_pyramid(d, options.levels);

  FramePyramid pyramid;
  pyramid.levels.resize(size_t(options.levels));
  for (int l = 0; l < options.levels; ++l) {
    FramePyramidLevel& level = pyramid.levels[size_t(l)];
    level.camera = camera.scaled(options.first_level + l);
    level.vertices = compute_vertex_map(depths[size_t(l)], level.camera);
    level.normals = compute_normal_map(level.vertices);
  }
  if (color != nullptr) {
    IntensityImage intensity = intensity_from_color(*color);
    for (int l = 0; l < options.first_level; ++l) intensity = pyr_down_gaussian(intensity);
    add_intensity(pyramid, intensity);
  }
  return pyramid;
}

FramePyramid build_model_pyramid(const VertexMap& vertices, const NormalMap& normals,
                                 const IntensityImage* intensity, const PinholeCamera& camera, int levels) {
  if (levels < 1) throw Error("frame pyramid: levels must be >= 1, got " + std::to_string(levels));
  check_size(vertices.width(), vertices.height(), camera, "the vertex map");
  check_size(normals.width(), normals.height(), camera, "the normal map");
  if (intensity != nullptr) check_size(intensity->width(), intensity->height(), camera, "the intensity image");

  DepthImage z(vertices.width(), vertices.height(), 0.0f);
  for (size_t i = 0; i < z.size(); ++i) z.pixels()[i] = hf_model_depth_pixel(vertices.pixels()[i]);
  const std::vector<DepthImage> depths = build_depth_pyramid(z, levels);

  FramePyramid pyramid;
  pyramid.levels.resize(size_t(levels));
  for (int l = 0; l < levels; ++l) {
    FramePyramidLevel& level = pyramid.levels[size_t(l)];
    level.camera = camera.scaled(l);
    if (l == 0) {
      level.vertices = vertices;
      level.normals = normals;
    } else {
      level.vertices = compute_vertex_map(depths[size_t(l)], level.camera);
      level.normals = compute_normal_map(level.vertices);
    }
  }
  if (intensity != nullptr) add_intensity(pyramid, *intensity);
  return pyramid;
}

DepthImage depth_of(const VertexMap& vertices) {
  DepthImage d(vertices.width(), vertices.height(), 0.0f);
  for (int y = 0; y < vertices.height(); ++y)
    for (int x = 0; x < vertices.width(); ++x)
      if (vertices(x, y).w != 0.0f) d(x, y) = vertices(x, y).z;
  return d;
}

}  // namespace hf
