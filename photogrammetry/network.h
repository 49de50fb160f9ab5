// The photogrammetric network of Kellner's "Guided 2D Modeling of 3D Buildings using Oriented Photos" (section 3):
// oriented photos ("shots") and a point cloud with per-point colour and visibility, in one world frame.
//
// Conventions (as OpenMVS and Middlebury): x_cam = R (X - C), pixel = K x_cam / z_cam. R rotates world into camera
// (rows: the camera's x right, y down, z forward axes in world coordinates), C is the camera centre in the world.
// Pixels are OpenCV's: u right, v down, the top-left pixel's centre at (0, 0). Units are the network's (SfM units for
// Sceaux, the gantry's for Middlebury, metres for hashfusion runs); nothing here assumes metres.
// No lens distortion: the readers take undistorted images (OpenMVS exports them, Middlebury's are calibrated so).
//
// Failure modes: validate() throws hf::Error naming the source and the first bad shot or point; readers call it, so
// every Network a reader returns has finite cameras with fx, fy > 0, orthonormal R (within 1e-6), a positive image
// size, unique shot names and visibility indices inside the shot list. Shots whose image file is absent are kept
// (their cameras still matter for the cloud's visibility) with image_available = false.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/image.h"

namespace hf::photogrammetry {

using Matrix34d = Eigen::Matrix<double, 3, 4>;

struct Shot {
  std::string name;        // the image's file name ("templeR0013.png"): how SKETCH.json names the shot; unique
  std::string image_path;  // where the image is (may be absent: image_available)
  bool image_available = false;
  int width = 0, height = 0;  // pixels
  Eigen::Matrix3d K = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d R_camera_world = Eigen::Matrix3d::Identity();  // x_cam = R (X - C)
  Eigen::Vector3d C_world = Eigen::Vector3d::Zero();

  // K [R | -R C]: the homogeneous projection, pixel ~ P [X; 1].
  Matrix34d P() const;
  Eigen::Vector3d to_camera(const Eigen::Vector3d& X_world) const { return R_camera_world * (X_world - C_world); }
  // The pixel of a world point in front of the camera (z_cam > 0), else nullopt; may lie outside the image.
  std::optional<Eigen::Vector2d> project(const Eigen::Vector3d& X_world) const;
  // Unit direction in the world of the ray from C through pixel uv.
  Eigen::Vector3d ray_world(const Eigen::Vector2d& uv) const;
  // Inside the image's pixel centres: 0 <= u <= width - 1, 0 <= v <= height - 1.
  bool in_image(const Eigen::Vector2d& uv) const;
  // Focal length in pixels (the mean of K's two), for converting world sizes at a depth into pixels.
  double focal_px() const { return 0.5 * (K(0, 0) + K(1, 1)); }
};

// The network's point cloud. `views` lists, per point, the indices of the shots that observed it (empty: unknown,
// e.g. a fused mesh's vertices); colours are empty or one per point.
struct Cloud {
  std::vector<Eigen::Vector3d> positions;
  std::vector<Rgb8> colors;
  std::vector<std::vector<int>> views;  // empty or one list per point

  size_t size() const { return positions.size(); }
  // Whether point i may be projected into shot s: unknown visibility admits every shot.
  bool visible_in(size_t i, int s) const;
};

struct Network {
  std::string source;  // what it was read from, for messages
  std::vector<Shot> shots;
  Cloud cloud;

  // Index of the shot named `name`, or -1.
  int shot_index(const std::string& name) const;
  // Throws hf::Error "SOURCE: shot 'NAME': ..." / "SOURCE: point N: ..." (see the header comment).
  void validate() const;
};

// The shot's image, checked to be the shot's size. Throws hf::Error naming the file when it is absent, unreadable or
// of another size (core/bounded_read.h limits apply through io/image_io.h).
ColorImage load_shot_image(const Shot& shot);

}  // namespace hf::photogrammetry
