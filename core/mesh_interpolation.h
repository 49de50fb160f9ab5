// Triangle-mesh reconstruction of an image given at some pixels only (Siekawa, section 3.2): the samples are
// triangulated (Delaunay, OpenCV's Subdiv2D) and every empty pixel inside a triangle takes the barycentric
// (linear) interpolation of its three corners' values. The alternative to push-pull (core/push_pull.h): smoother
// (no blocky pull) but blurring, and it leaves the pixels outside the samples' convex hull empty.
//
// Same in-place contract and statuses as push_pull_fill (values: width * height * channels floats, mask: one byte
// per pixel, non-zero = sample; on return mask 1 wherever a pixel holds a value; NaN / inf samples are dropped;
// no NaN written). Fewer than three samples, or collinear ones, make no triangle: the samples are kept, the rest
// stays empty. Thread-safety: pure.
#pragma once

#include <cstdint>

#include "core/push_pull.h"

namespace hf {

struct MeshInterpolationResult {
  PushPullResult fill;  // status, filled / empty pixels, dropped samples (levels = 0)
  long triangles = 0;   // Delaunay triangles inside the image
};

MeshInterpolationResult mesh_interpolate(int width, int height, int channels, float* values, std::uint8_t* mask);

}  // namespace hf
