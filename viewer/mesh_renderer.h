// Rendering a triangle mesh, trajectories and camera frusta with OpenGL 3.3 core into an offscreen framebuffer of
// a pinhole camera's size, read back as an image.
//
// The projection is the pinhole camera's, pixel centres at integers as everywhere in hashfusion: a world point p
// lands on pixel (fx X/Z + cx, fy Y/Z + cy) of p_camera = T_world_camera^-1 p, exactly as the CPU raycast
// (fusion/raycast.h) sees it. Surfaces are shaded with the same head-light formula as the raycast's `shaded`
// image (hf_headlight_shade, fusion/kernels/raycast_kernels.h: 0.2 + 0.7 c + 0.1 c^16, c = n . v clamped at 0),
// grey, or modulated by vertex colour with `use_colors` (a black vertex keeps the grey: fusion::colored_shading's
// rule for "no colour fused"); so a GL render of a TSDF's mesh and the CPU raycast of the
// same TSDF from the same pose differ only by where marching cubes and the ray's refined crossing put the surface.
// Background black (as the raycast's no-hit pixels). Lines: world-space polylines in one colour each.
// Requires a current GlContext on the calling thread; throws hf::Error naming the GL failure.
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "io/mesh.h"

namespace hf::viewer {

struct Polyline {
  std::vector<Eigen::Vector3f> points_world;
  Rgb8 color{255, 255, 255};
  bool strip = true;  // false: independent segments (pairs of points)
};

class MeshRenderer {
 public:
  MeshRenderer();
  ~MeshRenderer();
  MeshRenderer(const MeshRenderer&) = delete;
  MeshRenderer& operator=(const MeshRenderer&) = delete;

  // Uploads the mesh (replacing the previous one). Vertex normals are required for shading; a mesh without them
  // gets face normals (flat shading).
  void set_mesh(const TriangleMesh& mesh);
  bool has_mesh() const { return triangles_ > 0; }
  // Uploads a backdrop: an image with a depth per pixel (metres along the optical axis, 0 = nothing there), such as
  // a raycast of the TSDF (fusion/raycast.h), drawn first in every draw() over the whole viewport, each pixel at its
  // depth, so the mesh and lines drawn after it are hidden where the backdrop's surface is nearer. Pixels of depth 0
  // are left as they were (the clear colour). The backdrop must have been rendered with the camera and pose that
  // draw() / render() are given (same size for render(); a viewport of another size scales it, nearest texel), or
  // lines land off its surfaces. An empty image removes it.
  void set_backdrop(const ColorImage& image, const DepthImage& depth_m);

  // Draws the mesh and lines from T_world_camera with `camera` into the framebuffer and returns the image (RGB,
  // row 0 at the top).
  ColorImage render(const PinholeCamera& camera, const SE3& T_world_camera, const std::vector<Polyline>& lines = {},
                    bool use_colors = false);

  // Draws the same into the current default framebuffer's viewport region (x, y, w, h in window pixels, origin
  // bottom-left) instead of reading back; for the interactive window.
  void draw(const PinholeCamera& camera, const SE3& T_world_camera, const std::vector<Polyline>& lines,
            bool use_colors);

 private:
  struct Gl;
  std::unique_ptr<Gl> gl_;
  int triangles_ = 0;
  Eigen::Vector3f mesh_lo_ = Eigen::Vector3f::Zero(), mesh_hi_ = Eigen::Vector3f::Zero();  // its bounding box
  bool backdrop_ = false;
};

// The frustum of a camera at T_world_camera as line segments, `depth_m` deep.
Polyline camera_frustum(const PinholeCamera& camera, const SE3& T_world_camera, double depth_m, Rgb8 color);

}  // namespace hf::viewer
