// Physical bounds on camera intrinsics, checked wherever a camera is read from a file (core/camera.h's
// PinholeCamera::parse / load, io/seven_scenes.h's camera-intrinsics.txt). A focal length of 1e-300 or 1e300 px is
// finite, yet every frame downstream would be lost without a reason given.
#pragma once

#include <map>
#include <string>

#include "core/camera.h"

namespace hf {

// Focal lengths a camera file may state, per pixel of the image size: 1 / (2 tan 85 deg) and 1 / (2 tan 0.25 deg),
// i.e. fields of view of 170 .. 0.5 degrees.
inline constexpr double kMinFocalPerPixel = 0.0437;
inline constexpr double kMaxFocalPerPixel = 114.6;

// Throws hf::ParseError "FILE:LINE: expected fx within 27.968..73344 px (fields of view 0.5..170 degrees over 640
// px), got 1e-300" when fx / fy lie outside kMinFocalPerPixel..kMaxFocalPerPixel times the width / height, or the
// principal point more than one image size outside the image (cx in -width..2 width, cy likewise). `key_lines`
// gives the line of "fx", "cy", ... in `file` (absent: line 0). Numbers are printed short (core/number_text.h).
void check_camera_intrinsics(const PinholeCamera& camera, const std::string& file,
                             const std::map<std::string, int>& key_lines = {});

// The largest |coefficient| a camera file may give for k1 k2 k3 and for p1 p2: real Kinect / webcam lenses stay
// below 2 and 0.05 (TUM fr1: 0.26 -0.95 -0.005 0.003 1.16); 1e3 and 1 leave room for wide lenses yet refuse 1e300.
inline constexpr double kMaxRadialDistortion = 1e3;
inline constexpr double kMaxTangentialDistortion = 1.0;

// Throws hf::ParseError "FILE:LINE: expected k2 within -1000..1000, got 1e+300" for a coefficient outside the bounds
// above, and "FILE:LINE: expected a distortion whose image radius grows with the ray's angle over the whole image,
// ..." when the radial part folds back inside the image (its remap would not be one-to-one: two rays at one
// pixel). `camera` gives the image extent (its intrinsics already checked); `key_lines` as above.
void check_lens_distortion(const PinholeCamera& camera, const std::string& file,
                           const std::map<std::string, int>& key_lines = {});

}  // namespace hf
