// Analytic depth images for the core tests, in the camera frame: planes and spheres rendered exactly (through
// tests/common/analytic_depth.h with the identity pose), so tests can compare pyramids, filters and normals
// against the true surface.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <random>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "tests/common/analytic_depth.h"

namespace hf::test {

// Ray through pixel (x, y) with z = 1 (camera frame).
inline Eigen::Vector3d pixel_ray(const PinholeCamera& cam, double x, double y) {
  return {(x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0};
}

// Plane {p : n . p = dist_m} (n unit, dist_m > 0: n points away from the camera). Depth = z of the ray hit.
inline double plane_depth(const PinholeCamera& cam, const Eigen::Vector3d& n, double dist_m, double x, double y) {
  const double nr = n.dot(pixel_ray(cam, x, y));
  return nr > 0.0 ? dist_m / nr : 0.0;
}

inline DepthImage render_plane(const PinholeCamera& cam, const Eigen::Vector3d& n, double dist_m) {
  return testing::render_plane_depth(cam, SE3(), n, dist_m);
}

inline DepthImage render_sphere(const PinholeCamera& cam, const Eigen::Vector3d& centre, double radius_m) {
  return testing::render_sphere_depth(cam, SE3(), centre, radius_m);
}

// Adds N(0, sigma_m^2) to every valid pixel (deterministic for a given seed).
inline void add_depth_noise(DepthImage& d, double sigma_m, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0.0, sigma_m);
  for (float& v : d.pixels())
    if (v > 0.0f) v = float(v + noise(rng));
}

// A small camera for fast tests: the "ros" preset at pyramid level `level`.
inline PinholeCamera test_camera(int level) { return PinholeCamera::preset("ros").scaled(level); }

}  // namespace hf::test
