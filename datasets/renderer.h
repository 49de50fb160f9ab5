// CPU ray caster for analytic scenes: exact depth, incidence angle and shaded colour per pixel.
//
// For pixel (u, v) the ray is o + t d with o the camera centre and d = R_world_camera ((u - cx)/fx, (v - cy)/fy, 1),
// so the hit parameter t is the depth z along the optical axis (metres), exact to double precision before it is
// stored as float. Pixels whose ray hits nothing get depth 0. Colour is Lambertian: albedo * (ambient + diffuse *
// max(0, n . l)) with a world-fixed directional light, so a surface point has the same colour from every
// viewpoint (brightness constancy holds exactly without noise and exposure changes).
// Parallel over rows (TBB); the result does not depend on the thread count.
#pragma once

#include <Eigen/Core>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "datasets/scene.h"
#include "datasets/sensor_noise.h"

namespace hf::datasets {

struct Lighting {
  Eigen::Vector3d to_light_world{0.3, 0.5, 1.0};  // direction towards the light (normalised when used)
  double ambient = 0.45;
  double diffuse = 0.55;
};

struct RenderedView {
  DepthImage depth;            // metres along the optical axis, 0 = no surface
  Image<float> incidence_rad;  // angle between the viewing ray and the surface normal, radians, [0, pi/2]
  ColorImageF color;           // linear RGB in [0, 1] (black where there is no surface)
};

RenderedView render_view(const Scene& scene, const PinholeCamera& camera, const SE3& T_world_camera,
                         const Lighting& lighting = {});

}  // namespace hf::datasets
