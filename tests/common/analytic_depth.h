// Exact depth images of analytic planes and spheres seen from any pose (double precision ray casts, stored as
// float), shared by the core and fusion tests so both compare against one definition of the true surface.
#pragma once

#include <cmath>

#include <Eigen/Core>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"

namespace hf::testing {

// Depth along the optical axis of the sphere (centre_world, radius_m) seen by camera at T_world_camera; 0 = miss.
inline DepthImage render_sphere_depth(const PinholeCamera& camera, const SE3& T_world_camera,
                                      const Eigen::Vector3d& centre_world, double radius_m) {
  DepthImage depth(camera.width, camera.height, 0.0f);
  const Eigen::Matrix3d R = T_world_camera.rotation();
  const Eigen::Vector3d o = T_world_camera.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d dir = R * camera.backproject(u, v, 1.0);  // t along dir = depth
      const Eigen::Vector3d oc = o - centre_world;
      const double a = dir.squaredNorm(), b = 2.0 * dir.dot(oc), c = oc.squaredNorm() - radius_m * radius_m;
      const double disc = b * b - 4 * a * c;
      if (disc < 0) continue;
      const double t = (-b - std::sqrt(disc)) / (2 * a);
      if (t > 0) depth(u, v) = float(t);
    }
  }
  return depth;
}

// Depth of the plane {x : n . x = offset} (n unit, world frame); 0 where the ray misses or hits behind.
inline DepthImage render_plane_depth(const PinholeCamera& camera, const SE3& T_world_camera,
                                     const Eigen::Vector3d& n_world, double offset) {
  DepthImage depth(camera.width, camera.height, 0.0f);
  const Eigen::Matrix3d R = T_world_camera.rotation();
  const Eigen::Vector3d o = T_world_camera.translation();
  for (int v = 0; v < camera.height; ++v) {
    for (int u = 0; u < camera.width; ++u) {
      const Eigen::Vector3d dir = R * camera.backproject(u, v, 1.0);
      const double denom = n_world.dot(dir);
      if (std::abs(denom) < 1e-12) continue;
      const double t = (offset - n_world.dot(o)) / denom;
      if (t > 0) depth(u, v) = float(t);
    }
  }
  return depth;
}

}  // namespace hf::testing
