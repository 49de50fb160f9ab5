// The per-level maps registration works on, built once per frame and shared by every method.
//
//   hf::FramePyramid cur = hf::build_frame_pyramid(depth, color, camera);       // from a sensor frame
//   hf::FramePyramid ref = hf::build_model_pyramid(vertices, normals, &intensity, camera);  // raycast maps
//
// Level 0 is full resolution; level l has camera.scaled(l) and half the size of level l-1 (core/pyramid.h).
// Frames: vertices and normals in the frame's own camera frame (x right, y down, z forward, metres).
#pragma once

#include <vector>

#include "core/camera.h"
#include "core/device_copy.h"
#include "core/image.h"

namespace hf {

struct FramePyramidLevel {
  PinholeCamera camera;   // camera.scaled(level)
  VertexMap vertices;     // w = 1 valid
  NormalMap normals;      // unit, towards the camera, w = 1 valid
  IntensityImage intensity;  // [0, 1]; empty when the frame had no colour
  Image<float> grad_x, grad_y;  // of intensity (Sobel / 8, intensity units per pixel); empty without colour
  // Device copies of these maps (core/device_copy.h): filled by the device pyramid (registration/opencl/
  // device_pyramid.h), empty on the cpu; a copied level has none. Whoever writes a map of the level in place drops
  // its copy first.
  DeviceCopies device_copies;
  int width() const { return camera.width; }
  int height() const { return camera.height; }
  bool has_intensity() const { return !intensity.empty(); }
};

struct FramePyramid {
  std::vector<FramePyramidLevel> levels;  // [0] finest
  int num_levels() const { return int(levels.size()); }
  bool has_intensity() const { return !levels.empty() && levels[0].has_intensity(); }
};

struct FramePyramidOptions {
  int levels = 3;                  // KinectFusion: 3
  bool bilateral_filter = true;    // KinectFusion eq. 2 on level 0 depth before the vertex/normal maps
                                   // (core/filters.h defaults: 7x7 window, sigma_s 4.5 px, sigma_r 30 mm)
  float max_depth_m = 0.0f;        // depths beyond this are dropped (0 = keep all)
  float min_depth_m = 0.0f;        // depths below this are dropped
  // Build only from this level of the input down: the result's level 0 has camera.scaled(first_level). The depth is
  // first halved first_level times (depth-aware, core/pyramid.h) and the bilateral filter runs at that resolution;
  // intensity is Gaussian-downsampled the same number of times. Tracking at 320x240 from a 640x480 sensor thus
  // never pays for full-resolution filtering, vertex and normal maps.
  int first_level = 0;
  // Push-pull hole fill of the tracking depth (core/push_pull.h, Siekawa), after the first_level halvings and
  // before the bilateral filter: 0 = off; L > 0 fills a hole pixel when its aligned 2^L x 2^L block at that
  // resolution holds a measurement (small holes only). The tracking pyramid only: integration never sees it.
  // Off by default: bench/results/fewer_rays_render.md (depth holes) has the ATE with and without.
  int fill_holes_levels = 0;
};

// From a depth image (metres, 0/NaN invalid) and an optional colour image of the same size (nullptr: no
// intensity, so only geometric methods can use the pyramid). Never throws for bad depth values (all-NaN depth
// gives empty maps); throws hf::Error when the sizes disagree with the camera, the image is too small for the
// requested levels, or levels < 1.
FramePyramid build_frame_pyramid(const DepthImage& depth, const ColorImage* color, const PinholeCamera& camera,
                                 const FramePyramidOptions& options = {});

// The z of a vertex map as a depth image (0 where invalid): e.g. a pyramid level's depth, to fuse or compare.
DepthImage depth_of(const VertexMap& vertices);

// From model maps (e.g. a raycast; camera frame of the raycast camera) and an optional intensity image. Level 0
// uses the maps as given; coarser levels re-derive vertices and normals from the depth-aware pyramid of the
// vertices' z. Same errors as build_frame_pyramid.
FramePyramid build_model_pyramid(const VertexMap& vertices, const NormalMap& normals,
                                 const IntensityImage* intensity, const PinholeCamera& camera, int levels = 3);

}  // namespace hf
