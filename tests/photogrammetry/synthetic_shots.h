// Synthetic shots for the photogrammetry tests: pinhole cameras looking at a target, deterministic.
#pragma once

#include <Eigen/Geometry>
#include <string>

#include "photogrammetry/network.h"

namespace hf::photogrammetry::testing {

// A shot at C looking at `target` with the world's +z as "up" (image v down), focal f px, principal point at the
// image centre.
inline Shot look_at(const std::string& name, const Eigen::Vector3d& C, const Eigen::Vector3d& target, double f = 500,
                    int width = 640, int height = 480, Eigen::Vector3d up = Eigen::Vector3d::UnitZ()) {
  Shot s;
  s.name = name;
  s.image_path = "/nonexistent/" + name;
  s.width = width;
  s.height = height;
  s.K << f, 0, (width - 1) / 2.0, 0, f, (height - 1) / 2.0, 0, 0, 1;
  const Eigen::Vector3d z = (target - C).normalized();
  if (std::fabs(z.dot(up)) > 0.99) up = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = z.cross(up).normalized();  // right
  const Eigen::Vector3d y = z.cross(x);                // down
  s.R_camera_world.row(0) = x.transpose();
  s.R_camera_world.row(1) = y.transpose();
  s.R_camera_world.row(2) = z.transpose();
  s.C_world = C;
  return s;
}

}  // namespace hf::photogrammetry::testing
