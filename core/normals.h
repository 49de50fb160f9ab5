// Vertex and normal maps from depth (KinectFusion section 3.2, report eq. 3).
//
// Frames: both maps are in the camera frame of the depth image (x right, y down, z forward, metres).
// Maps are hf_float4 with w = 1 valid and w = 0 invalid (all components 0), never NaN.
// The per-pixel maths is in core/kernels/image_kernels.h (hf_vertex_pixel, hf_normal_pixel); these are the CPU
// loops (parallel over rows with TBB, deterministic). Pure functions, safe to call from several threads.
#pragma once

#include "core/camera.h"
#include "core/image.h"

namespace hf {

// v(x, y) = backproject(x, y, depth(x, y)); invalid where the depth is 0, NaN, inf or negative.
// Throws hf::Error when the camera's size differs from the image's (use camera.scaled(level) for level l).
VertexMap compute_vertex_map(const DepthImage& depth, const PinholeCamera& camera);

struct NormalParams {
  // Neighbours whose depth differs from the centre by more than this fraction of the centre depth are across a
  // depth discontinuity and are not used (0.05: 5 cm at 1 m; a plane only reaches that step between adjacent
  // pixels at f = 525 px when inclined more than ~88 degrees to the viewing ray, while sensor noise at 4 m is
  // under 1% of the depth).
  float max_depth_jump_ratio = 0.05f;
};

// Unit normals oriented towards the camera (n . v < 0) from central differences of the vertex map, falling back
// to one-sided differences next to invalid vertices and depth discontinuities; invalid where a vertex has no
// usable neighbour along x or y. Throws hf::Error when max_depth_jump_ratio is not finite and positive.
NormalMap compute_normal_map(const VertexMap& vertices, const NormalParams& params = {});

}  // namespace hf
