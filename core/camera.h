// Pinhole camera model (equations 3-8 of Stotko's registration report, shared/seeds INDEX.md).
//
// Pixel coordinates: x to the right, y down, integer values at pixel centres, (0,0) the top-left pixel.
// Camera frame: x right, y down, z forward (optical axis), metres. A camera may carry lens distortion
// (LensDistortion, OpenCV's 5-coefficient model) of the images as stored; every projection here is the pinhole's,
// so a distorted camera's frames are undistorted once on arrival (core/undistort.h; slam::Pipeline does it) and
// tracked and fused with pinhole() alone.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/kernels/cl_compat.h"

namespace hf {

// Brown-Conrady lens distortion in OpenCV's order and convention (k1 k2 p1 p2 k3): the point at normalised
// pinhole coordinates (x, y) = (X / Z, Y / Z) is imaged at normalised (x_d, y_d), i.e. pixel (fx x_d + cx,
// fy y_d + cy), with r^2 = x^2 + y^2 and
//   x_d = x (1 + k1 r^2 + k2 r^4 + k3 r^6) + 2 p1 x y + p2 (r^2 + 2 x^2)
//   y_d = y (1 + k1 r^2 + k2 r^4 + k3 r^6) + p1 (r^2 + 2 y^2) + 2 p2 x y.
// All zero (the default): none.
struct LensDistortion {
  double k1 = 0.0, k2 = 0.0, p1 = 0.0, p2 = 0.0, k3 = 0.0;

  bool none() const { return k1 == 0.0 && k2 == 0.0 && p1 == 0.0 && p2 == 0.0 && k3 == 0.0; }
  // (x_d, y_d) of the normalised pinhole point (x, y), by the equations above.
  Eigen::Vector2d distort(const Eigen::Vector2d& xy) const {
    const double x = xy.x(), y = xy.y(), r2 = x * x + y * y;
    const double radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    return {x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
            y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y};
  }
  bool operator==(const LensDistortion&) const = default;
};

struct PinholeCamera {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;
  // Of the images as stored (see the file comment); none for an undistorted or synthetic camera.
  LensDistortion distortion{};

  // Equation 3 / 7: the 3D point in the camera frame for pixel (px, py) at depth d (metres).
  Eigen::Vector3d backproject(double px, double py, double depth_m) const {
    return {(px - cx) / fx * depth_m, (py - cy) / fy * depth_m, depth_m};
  }
  // Equation 4 / 8: pixel of a point with v.z() > 0. The result may lie outside the image; see in_image().
  Eigen::Vector2d project(const Eigen::Vector3d& v) const {
    return {fx * v.x() / v.z() + cx, fy * v.y() / v.z() + cy};
  }
  bool in_image(const Eigen::Vector2d& p) const {
    return p.x() >= 0.0 && p.y() >= 0.0 && p.x() <= width - 1.0 && p.y() <= height - 1.0;
  }
  // Equation 5.
  Eigen::Matrix3d K() const;

  // The camera of pyramid level `level` where each level halves the resolution by 2x2 averaging. Pixel centres
  // move with the averaging: c_l = (c + 0.5) / 2^l - 0.5, f_l = f / 2^l (width and height round down).
  PinholeCamera scaled(int level) const;
  // The same intrinsics without distortion: the camera of the undistorted images.
  PinholeCamera pinhole() const {
    PinholeCamera c = *this;
    c.distortion = LensDistortion{};
    return c;
  }

  hf_intrinsics kernel_intrinsics() const {
    return hf_intrinsics{float(fx), float(fy), float(cx), float(cy), width, height};
  }

  bool operator==(const PinholeCamera&) const = default;

  // Named presets: "fr1", "fr2", "fr3" (TUM RGB-D, from the TUM web page; fr1 and fr2 with their published
  // k1 k2 p1 p2 k3, since their images are stored distorted), "fr1-registered" (532, 532, 309.5, 250: fr1's
  // stored images as one pinhole, estimated from fr1/rpy against its reference), "ros" (525, 525, 319.5, 239.5),
  // "icl-nuim" (481.2, 480, 319.5, 239.5: the TUM-format release of ICL-NUIM, whose y axis is already flipped),
  // "7scenes" (585, 585, 320, 240). Throws hf::Error on an unknown name listing the known ones.
  static PinholeCamera preset(const std::string& name);
  static std::vector<std::string> preset_names();

  // Camera file: either JSON {"fx":..,"fy":..,"cx":..,"cy":..,"width":..,"height":.., "k1":.., ...} or a text
  // file of "key value" lines with the same keys ('#' comments). fx fy cx cy width height are required; the
  // distortion keys k1 k2 p1 p2 k3 are optional (absent: 0). Throws hf::ParseError naming file and line for a
  // missing, repeated, unknown or non-finite value, intrinsics outside core/camera_bounds.h's bounds, and a
  // distortion outside check_lens_distortion's.
  static PinholeCamera load(const std::string& path);
  static PinholeCamera parse(const std::string& text, const std::string& name_for_errors);
  // Writes the JSON form atomically.
  void save(const std::string& path) const;
  std::string describe() const;  // "fx=... fy=... cx=... cy=... 640x480" (+ " k1=... k2=... p1=... p2=... k3=...")
};

}  // namespace hf
