// Rendering a triangle mesh (a head model, a fused reconstruction) the way render_view renders analytic scenes:
// the same RenderedView (depth along the optical axis, incidence angle, linear colour), so the sensor model
// (sensor_noise.h) applies unchanged.
//
// Z-buffer rasterisation on the CPU: every triangle in front of the camera is projected, and each pixel centre
// (u, v) inside it gets the exact ray-plane depth t of the ray ((u - cx)/fx, (v - cy)/fy, 1) with the triangle's
// plane (so the depth equals the ray caster's, not an interpolation of projected depths); the nearest t wins.
// Triangles with a vertex nearer than near_m are skipped (no clipping: a head seen from 0.5 m has none).
// Colour: the mesh's vertex colours averaged per triangle (0.8 grey without colours) times the Lambertian shade
// of render_view's Lighting on the triangle's normal facing the camera.
// Degenerate triangles (zero area) are skipped; pixels seeing nothing have depth 0. Deterministic, one thread.
#pragma once

#include "core/camera.h"
#include "core/se3.h"
#include "datasets/renderer.h"
#include "io/mesh.h"

namespace hf::datasets {

RenderedView render_mesh(const TriangleMesh& mesh_world, const PinholeCamera& camera, const SE3& T_world_camera,
                         const Lighting& lighting = {}, double near_m = 0.05);

}  // namespace hf::datasets
