// Integrate(depth, colour, camera, T_world_camera): fuse one RGB-D frame into the voxel-hashed TSDF.
//
// Two phases (Niessner et al. 2013):
//   1. Allocation. Every valid depth pixel d (finite, in [min_depth_m, max_depth_m]) walks its viewing ray over the
//      depth band [d - mu, d + mu] with a 3-D DDA over blocks and allocates each block it crosses. Free space in
//      front of the band is never allocated; NaN, inf, zero and out-of-range depth allocate nothing. Blocks the
//      frame touches that were streamed out (in `store`) are brought back first, so a block lives in one place.
//   2. Update. The blocks touched in phase 1 (the visible set) are updated in parallel over blocks (TBB); each
//      block runs the shared per-voxel kernel (fusion/kernels/integrate_kernels.h: projective TSDF, running
//      average of eq. 57-58, weight cap, colour with the same weights) with the voxel centre moved incrementally
//      through the block. Blocks whose corners all project outside the image or behind the camera are skipped.
//
// Frames: T_world_camera maps camera points to world (the pose of the camera). Units: metres.
// Errors: hf::Error when the depth/colour sizes do not match the camera; CapacityError when the pool is full
// (the frame is then partly allocated but no voxel has been updated).
// Thread-safety: one integrate() per grid at a time; it uses all cores itself.
#pragma once

#include <cstddef>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

struct IntegrateParams {
  double min_depth_m = 0.1;        // nearer pixels are ignored (sensor minimum range)
  double max_depth_m = 8.0;        // farther pixels are ignored (Kinect noise grows as d^2)
  float observation_weight = 1.0f;  // w_{t+1} of eq. 57 for every observation
};

struct IntegrateStats {
  size_t pixels_used = 0;          // depth pixels that allocated along their ray
  size_t blocks_allocated = 0;     // blocks created by this frame (including ones streamed back in)
  size_t blocks_streamed_in = 0;   // of those, blocks brought back from the store
  size_t blocks_visible = 0;       // blocks updated by this frame
  size_t voxels_updated = 0;       // voxels whose value changed (observed by the frame)
  size_t blocks_total = 0;         // grid.block_count() afterwards
  size_t memory_bytes = 0;         // grid.memory_bytes() afterwards
  double allocate_ms = 0.0;
  double update_ms = 0.0;
};

// Fuses depth (metres, 0 = none) and optionally colour (empty image = no colour; else the same size as depth)
// seen by `camera` (whose size must equal the depth's) from pose T_world_camera.
IntegrateStats integrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                         const PinholeCamera& camera, const SE3& T_world_camera, const IntegrateParams& params = {},
                         BlockStore* store = nullptr);

// Phase 1 alone: the sorted, unique coordinates of the blocks that depth touches (nothing is allocated).
std::vector<BlockCoord> blocks_touched_by(const VolumeParams& volume, const DepthImage& depth,
                                          const PinholeCamera& camera, const SE3& T_world_camera,
                                          const IntegrateParams& params = {}, size_t* pixels_used = nullptr);

}  // namespace hf::fusion
