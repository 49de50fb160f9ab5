// Undistortion of a distorted camera's images by a remap computed once (OpenCV's initUndistortRectifyMap +
// remap, without OpenCV): the output is what the camera's pinhole() would have seen.
//
// For each output pixel (u, v) the normalised pinhole point ((u - cx) / fx, (v - cy) / fy) is distorted
// (LensDistortion::distort) and projected with the same fx fy cx cy: that is where the stored image saw the ray.
// Depth takes the nearest stored pixel, never a blend: a depth interpolated across an object's edge is a point
// that exists on neither surface (the same reason the pyramid's depth levels skip invalid neighbours). The depth
// value itself is kept: a Kinect stores z along the optical axis, which lens distortion moves sideways in the image
// but does not change. Colour is interpolated bilinearly. Output pixels whose ray the stored image did not see
// (a band along the border for fr1's lens, whose radial factor grows to 1.075 at the corners) get depth 0 (no
// measurement) and the nearest border colour (not black: a fixed black frame is an edge that never moves, which
// photometric alignment locks onto).
//
// TUM's fr1 / fr2 depth is registered to the distorted colour image, so both are undistorted with the colour
// camera's model.
//
// Thread-safety: const methods only after construction; each call runs its rows in parallel (core/parallel.h).
#pragma once

#include <cstdint>
#include <vector>

#include "core/camera.h"
#include "core/image.h"

namespace hf {

class Undistorter {
 public:
  // `camera` is the distorted camera (its distortion may be none: then the remap is the identity).
  explicit Undistorter(const PinholeCamera& camera);

  // The camera of the output images: camera.pinhole().
  const PinholeCamera& camera() const { return pinhole_; }

  // The input must have the camera's size (throws hf::Error otherwise); an empty colour image stays empty.
  DepthImage depth(const DepthImage& distorted) const;
  ColorImage color(const ColorImage& distorted) const;

 private:
  // Per output pixel: the nearest source pixel's index, or -1 where the ray falls outside the stored image.
  std::vector<std::int32_t> nearest_;
  // Per output pixel: the top-left source pixel of the (border-clamped) bilinear footprint and the weights of the
  // right and lower neighbours, in 1/256 (integer blending keeps colour exact for a uniform patch).
  std::vector<std::int32_t> corner_;
  std::vector<std::uint8_t> wx_, wy_;
  PinholeCamera pinhole_;
};

}  // namespace hf
