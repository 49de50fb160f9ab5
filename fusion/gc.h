// Garbage collection of blocks that end up empty.
//
// A block is garbage when no marching-cubes cell or ray can find a surface in it:
//   - unobserved: every voxel has weight 0 (e.g. allocated by a ray whose band it only grazed), or
//   - free space: every observed voxel holds sdf = +1 (saturated: at least mu in front of any surface, which is
//     what carving leaves where an object moved away), with at least one observed voxel.
// Blocks saturated at -1 (behind a surface) are kept: they border surface blocks, and the zero crossing between
// them and a positive neighbour lies in the cell spanning both. A +1 voxel cannot border a crossing in a
// consistent TSDF (its neighbours are at least mu - 1 voxel from the surface), so dropping +1 blocks loses nothing.
//
// Cost: one pass over every voxel of the grid; call it every few dozen frames, not per frame.
// Thread-safety: exclusive access to the grid.
#pragma once

#include <cstddef>

#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

struct GcParams {
  bool release_unobserved = true;  // all weights 0
  bool release_free_space = true;  // all observed voxels at sdf = +1
};

// True when `block` is garbage under `params`.
bool block_is_empty(const VoxelBlock& block, const GcParams& params = {});

// Releases every empty block; returns the number released.
size_t garbage_collect(VoxelBlockGrid& grid, const GcParams& params = {});

}  // namespace hf::fusion
