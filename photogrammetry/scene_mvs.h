// OpenMVS's binary scene (scene.mvs: the MVS::Interface of OpenMVS's libs/MVS/Interface.h, versions 0 to 7) as a
// photogrammetric network (photogrammetry/network.h).
//
// Layout (little-endian; a string is a uint64 length and its bytes, an array a uint64 count and its elements):
//   header      "MVSI", uint32 version, uint32 reserved; a file without it is version 0 (the first, headerless one)
//   platforms   [name, cameras [name, bandName (v >= 4), width, height (uint32, v >= 1), K, R (9 doubles, row
//               major), C (3 doubles)], poses [R (9 doubles), C (3 doubles)]]
//   images      [name, maskName (v >= 5), platformID, cameraID, poseID, ID (v >= 3) (uint32),
//               minDepth, avgDepth, maxDepth (float), viewScores [6 x 4 bytes] (v >= 7)]
//   vertices    [X (3 floats), views [imageID (uint32), confidence (float)]]
//   verticesNormal [3 floats], verticesColor [B, G, R (uint8)]
//   lines, linesNormal, linesColor (v >= 1), transform (16 doubles, v >= 2), obb (15 doubles, v >= 6)
// An image's camera is its platform camera at its platform pose: R = R_camera R_pose, C = R_pose^T C_camera + C_pose
// (x_cam = R (X - C), OpenMVS's convention and ours). Images without a pose (poseID = 0xFFFFFFFF) are not shots;
// a point's views are renumbered to the shots kept (views of unposed images dropped). K must be at the camera's
// resolution (width, height > 0); a normalised K (no resolution stored) is refused, as the image size it needs
// lives only in the image file. Shot::name is the image name's file name, image_path the name relative to
// image_root (absolute names stay absolute). Colours come from verticesColor when it has one per vertex, else
// none. The file's `transform` (relative to absolute coordinates) is not applied: the network stays in the frame the
// cameras and points are stored in, as the text dump (scene_readers.h) does.
//
// Limits: kMaxShots images, kMaxCloudPoints vertices, strings up to 4096 bytes; every count is checked against the
// bytes left before anything is allocated, so a hostile count cannot exhaust memory.
// Failure modes: hf::ParseError "FILE: at byte N: expected ..." for truncated or malformed content (unsupported
// version, IDs out of range, non-finite numbers, trailing bytes); Network::validate()'s hf::Error for inconsistent
// cameras.
#pragma once

#include <string>
#include <string_view>

#include "photogrammetry/network.h"

namespace hf::photogrammetry {

inline constexpr unsigned kMaxSceneMvsVersion = 7;

// The bytes of a scene.mvs file; name_for_errors replaces the path in messages.
Network parse_scene_mvs(std::string_view bytes, const std::string& name_for_errors, const std::string& image_root);
// A scene.mvs file (images relative to its folder).
Network read_scene_mvs(const std::string& path);

}  // namespace hf::photogrammetry
