// The tracking raycast with fewer rays (issue 19): raycast() cast only at the pixels of a mask, the pixels whose
// model vertex and normal the registration will read.
//
//   // the frame's row selection (registration/pixel_selection.h), grown by the motion to the next frame
//   Image<std::uint8_t> rays = dilate_rays(select_pixels(frame_level, selection), 2);
//   raycast_sampled(grid, tracking_camera, T_world_camera, options, rays, &model);
//
// At a pixel with rays(x, y) != 0 the outputs equal raycast()'s with the same arguments bit for bit (the same
// stages: range image, ray cast, pixel write; tests/fusion/test_raycast.cpp holds them to it); every other pixel
// reads as a miss (depth 0, vertex and normal w = 0, colour black). hit_count counts the cast pixels' hits.
// Frames, units, options and thread-safety as raycast() (fusion/raycast.h). Throws hf::Error as raycast() does and
// when the mask's size is not the camera's.
//
// Why a mask and not a list: the SLAM pipeline's reference pyramid, depth-consistency check and next hint read the
// result as images; a mask keeps those unchanged and lets the work tiles skip rays in a cache-friendly order.
#pragma once

#include <cstdint>

#include "fusion/raycast.h"

namespace hf::fusion {

void raycast_sampled(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                     const RaycastOptions& options, const Image<std::uint8_t>& rays, RaycastResult* out);

// The mask grown by radius_px in x and y (a square window): the reference pixels a selected current pixel can
// land on when the camera moves by up to radius_px between the frames (after the motion prior). radius 0: a copy.
Image<std::uint8_t> dilate_rays(const Image<std::uint8_t>& rays, int radius_px);

}  // namespace hf::fusion
