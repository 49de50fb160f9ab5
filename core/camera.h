// Pinhole camera model (equations 3-8 of Stotko's registration report, shared/seeds INDEX.md).
//
// Pixel coordinates: x to the right, y down, integer values at pixel centres, (0,0) the top-left pixel.
// Camera frame: x right, y down, z forward (optical axis), metres. No lens distortion: TUM and 7-Scenes
// depth is already registered, and the presets carry only the pinhole part.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/kernels/cl_compat.h"

namespace hf {

struct PinholeCamera {
  double fx = 525.0, fy = 525.0, cx = 319.5, cy = 239.5;
  int width = 640, height = 480;

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

  hf_intrinsics kernel_intrinsics() const {
    return hf_intrinsics{float(fx), float(fy), float(cx), float(cy), width, height};
  }

  bool operator==(const PinholeCamera&) const = default;

  // Named presets: "fr1", "fr2", "fr3" (TUM RGB-D, from the TUM web page), "ros" (525, 525, 319.5, 239.5),
  // "icl-nuim" (481.2, 480, 319.5, 239.5: the TUM-format release of ICL-NUIM, whose y axis is already flipped),
  // "7scenes" (585, 585, 320, 240). Throws hf::Error on an unknown name listing the known ones.
  static PinholeCamera preset(const std::string& name);
  static std::vector<std::string> preset_names();

  // Camera file: either JSON {"fx":..,"fy":..,"cx":..,"cy":..,"width":..,"height":..} or a text file of
  // "key value" lines with the same keys ('#' comments). Throws hf::ParseError naming file and line.
  static PinholeCamera load(const std::string& path);
  static PinholeCamera parse(const std::string& text, const std::string& name_for_errors);
  // Writes the JSON form atomically.
  void save(const std::string& path) const;
  std::string describe() const;  // "fx=... fy=... cx=... cy=... 640x480"
};

}  // namespace hf
