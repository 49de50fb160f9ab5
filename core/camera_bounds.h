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

}  // namespace hf
