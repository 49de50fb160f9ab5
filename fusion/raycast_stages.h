// raycast()'s per-pixel loop for the variants that cast fewer rays (fusion/raycast_sampled.h), inside fusion/.
//
// raycast() runs three named stages (fusion/raycast.cpp, after InfiniTAM's split): the range image (the blocks in
// view projected to an 8 x 8-tile depth range: FindVisibleBlocks + CreateExpectedDepths), the ray cast (the march
// of one pixel's ray, around its hint first: GenericRaycast) and the pixel write (depth, vertex, colour, normal,
// shading). raycast_pixels runs them for every pixel (rays == nullptr: raycast() itself) or only where
// (*rays)(x, y) != 0, writing a miss elsewhere, so a cast pixel's outputs equal raycast()'s bit for bit.
#pragma once

#include <cstdint>

#include "fusion/raycast.h"

namespace hf::fusion {

// Throws hf::Error as raycast() does, and when the mask's size is not the camera's.
void raycast_pixels(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                    const RaycastOptions& options, const Image<std::uint8_t>* rays, RaycastResult* out);

}  // namespace hf::fusion
