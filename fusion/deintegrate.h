// Deintegrate(depth, colour, camera, T_world_camera): take one RGB-D frame back out of the voxel-hashed TSDF, so a
// frame whose pose the pose graph corrected can be fused again at its new pose (BundleFusion, Dai et al. 2017).
//
// What it undoes: exactly what integrate() (fusion/integrate.h) did for that frame, given the same images, camera,
// pose and IntegrateParams (observation_weight, point_to_plane, depth range). It finds the same blocks (phase 1,
// blocks_touched_by, without allocating), and in each one in view the same voxels with the same observed sdf,
// weight and colour (the shared hf_observe_voxel_at), and inverts the running average of eqs. 57-58 on them
// (hf_tsdf_downdate, fusion/kernels/integrate_kernels.h): W' = W - w, D' = (D W - d w) / W', colour likewise;
// W' <= 0 resets the voxel to unobserved.
//
// Guarantees, against the grid before the frame was integrated (the kernel header has the derivations):
//   - every voxel whose update did not reach the weight cap (W + w <= VolumeParams::max_weight) comes back within
//     its quantisation: weight exact (w and W multiples of 1/16), sdf within (W_after / W) / 2 + 1/2 of an int16
//     step (1 step for w <= W), colour within as many units; a voxel the frame alone had observed is unobserved;
//   - where the cap clipped the update, the frame's share cannot be known (the average forgets it): the inverse of
//     the update that reached the cap is taken (weight W_max - w, sdf off by at most 2 w^2 / (W_max^2 - w^2) of
//     mu when the voxel was already at the cap), so that integrate() of the same frame restores the voxel (up to
//     the quantisation, where the inverse did not leave [-1, 1]);
//   - a voxel whose first colour came from this frame keeps a colour (the voxel does not record which sample was
//     first); its sdf and weight follow the rules above;
//   - voxels changed by other frames since are not restored to anything: their other observations stay.
// Blocks: a block of the frame's set that was streamed out (in `store`) is brought back first, like integrate(); a
// block that no longer exists anywhere (collected) holds nothing of the frame and is skipped. Every block of the
// frame's set that ends with no observed voxel is released (garbage collection of what the frame emptied), and
// every block it changed gets its VoxelBlockGrid::surface_free flag again.
//
// Errors: hf::Error when the image sizes do not match the camera (nothing has been changed then).
// Thread-safety: exclusive access to the grid (it releases blocks); it uses all cores itself.
#pragma once

#include <cstddef>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/integrate.h"
#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

struct DeintegrateStats {
  size_t blocks_found = 0;        // blocks of the frame's set that existed (in the grid or the store)
  size_t blocks_streamed_in = 0;  // of those, blocks brought back from the store
  size_t blocks_visible = 0;      // blocks in view that were updated
  size_t voxels_updated = 0;      // voxels an observation was taken out of
  size_t blocks_released = 0;     // blocks of the frame's set left with no observed voxel, released
  size_t blocks_total = 0;        // grid.block_count() afterwards
  double find_ms = 0.0;           // phase 1 and the look-ups
  double update_ms = 0.0;         // includes incidence_ms
  double incidence_ms = 0.0;
  double release_ms = 0.0;
};

// Takes a frame integrate(grid, depth, colour, camera, T_world_camera, params, store) fused back out.
DeintegrateStats deintegrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                             const PinholeCamera& camera, const SE3& T_world_camera,
                             const IntegrateParams& params = {}, BlockStore* store = nullptr);

struct ReintegrateStats {
  DeintegrateStats deintegrated;
  IntegrateStats integrated;
};

// A frame whose pose changed: deintegrate() at the pose it was fused with, then integrate() at the new one.
ReintegrateStats reintegrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                             const PinholeCamera& camera, const SE3& T_world_camera_fused,
                             const SE3& T_world_camera_new, const IntegrateParams& params = {},
                             BlockStore* store = nullptr);

}  // namespace hf::fusion
