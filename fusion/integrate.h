// Integrate(depth, colour, camera, T_world_camera): fuse one RGB-D frame into the voxel-hashed TSDF.
//
// Two phases (Niessner et al. 2013):
//   1. Allocation. Every valid depth pixel d (finite, in [min_depth_m, max_depth_m]) walks its viewing ray over the
//      depth band [d - mu, d + mu] with a 3-D DDA over blocks and allocates each block it crosses. Free space in
//      front of the band is never allocated; NaN, inf, zero and out-of-range depth allocate nothing. Blocks the
//      frame touches that were streamed out (in `store`) are brought back first, so a block lives in one place.
//      A pixel whose band starts and ends in the same two blocks as its left or upper neighbour's is not walked
//      again (the segments are nearly parallel and a fraction of a block apart). On the room at 1 cm, 640x480,
//      54 k of the 304 k valid pixels per frame are walked (87 k when only the left neighbour counts), and the map
//      has 0.1 % fewer blocks than with the left-neighbour test alone (blocks one segment clips at a corner).
//   2. Update. The blocks touched in phase 1 (the visible set) are updated in parallel over blocks (TBB); each
//      block runs the shared per-voxel kernel (fusion/kernels/integrate_kernels.h: projective TSDF, running
//      average of eq. 57-58, weight cap, colour with the same weights), eight voxels of a block row at a time
//      with AVX2 where the processor has it (fusion/integrate_cpu.h; same bits as the voxel-by-voxel loop).
//      Blocks whose corners all project outside the image or behind the camera are skipped. Each block the frame
//      changed gets its VoxelBlockGrid::surface_free flag again (the raycast's block skip).
//      With IntegrateParams::point_to_plane, a per-pixel pass first computes each pixel's point-to-plane factor
//      from the depth image (hf_point_to_plane_factor) and the kernel scales the projective distance by it.
//
// Frames: T_world_camera maps camera points to world (the pose of the camera). Units: metres.
// Errors: hf::Error when the depth/colour sizes do not match the camera; CapacityError when the pool is full
// (the frame is then partly allocated but no voxel has been updated).
// Thread-safety: one integrate() per grid at a time, with no other reader of the grid meanwhile (it frees the hash
// arrays that growth retired: VoxelBlockGrid::free_retired_tables); it uses all cores itself.
#pragma once

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

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
  // Observed signed distance of a voxel: true = point-to-plane, the depth difference eta = d(u) - z turned into
  // the distance to the tangent plane of the surface pixel u sees (times |cos theta| |(x/z, y/z, 1)|, theta
  // between the viewing ray and the depth image's normal there; Bylow et al. 2013, hf_point_to_plane_factor);
  // false = projective eta alone (KinectFusion). Which voxels a frame updates, the truncation band and the colour
  // are decided by eta either way; point-to-plane costs one per-pixel pass.
  // Measured (tests/fusion, bench/results/fusion.md), 1 cm voxels, 320 x 240 frames:
  //   noise-free sphere seen from 30 poses all round: raycast normals 3.8 -> 1.7 degrees RMS (median 2.7 -> 0.8),
  //     mesh 0.076 -> 0.048 voxel RMS: the projective slopes 1 / cos theta differ between the views a voxel
  //     averages and bend the interpolated field; point-to-plane slopes agree;
  //   noise-free room (20 frames of a trajectory): mesh 95th percentile 0.155 -> 0.230 voxel (walls and floor
  //     unchanged; the ball and cylinder, seen from one side at grazing angles, 0.17 -> 0.35: a tangent plane
  //     extrapolated along a grazing ray misses a curved surface by (eta sin theta)^2 / 2r);
  //   noisy sphere (Kinect noise, 30 frames): mesh 0.105 -> 0.120 voxel RMS (noisy per-pixel normals).
  // So it is off by default (the SLAM pipeline fuses rooms from a trajectory) and on for objects scanned from all
  // around.
  bool point_to_plane = false;
  // Depth-dependent truncation (hf_truncation_scale, fusion/kernels/integrate_kernels.h): an observation at
  // measured depth d has the band mu * min(1, max(truncation_min_fraction, (d / truncation_depth_ref_m)^2)), as
  // the sensor's axial noise grows as d^2; values stay in units of the volume's mu, so the raycast and the sdf
  // tracker read the map unchanged. 0 = off (every band mu, KinectFusion), the default: measured in
  // bench/results/accuracy/ate_levers.md. The band only shrinks (allocation stays [d - mu, d + mu]). On the CPU
  // map only (the plain per-voxel loop, not the AVX2 one); the OpenCL map refuses it (hf::Error).
  float truncation_depth_ref_m = 0.0f;
  float truncation_min_fraction = 0.5f;  // the narrowest band, as a fraction of mu, in (0, 1]
  // Observation weight by depth (hf_weight_scale): an observation at measured depth d counts observation_weight
  // min(1, (weight_depth_ref_m / d)^2), floored at 1/8. 0 = off (every observation alike), the default; measured in
  // bench/results/accuracy/ate_levers.md. CPU map only, as truncation_depth_ref_m.
  float weight_depth_ref_m = 0.0f;
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
  double update_ms = 0.0;          // includes incidence_ms
  double incidence_ms = 0.0;       // the per-pixel pass of point_to_plane (hf_point_to_plane_factor)
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

namespace detail {

// What integrate() and deintegrate() (fusion/deintegrate.h) share. check_frame_sizes throws integrate's hf::Error for
// a depth / colour / camera size mismatch. update_blocks is phase 2 alone on the blocks phase 1 touched
// (blocks_touched_by), looked up by the caller with each block's surface_free flag (VoxelBlockGrid::allocate):
// for every block in view, integrate's update (VoxelUpdate::integrate) or its inverse (VoxelUpdate::deintegrate:
// hf_deintegrate_voxel_at, the same observations bit for bit), each changed block's flag kept. Fills stats'
// voxels_updated, blocks_visible, update_ms and incidence_ms.
void check_frame_sizes(const DepthImage& depth, const ColorImage& colour, const PinholeCamera& camera);
enum class VoxelUpdate { integrate, deintegrate };
void update_blocks(VoxelUpdate op, const VolumeParams& volume,
                   const std::vector<std::pair<BlockCoord, VoxelBlock*>>& blocks,
                   const std::vector<std::uint8_t*>& surface_free, const DepthImage& depth, const ColorImage& colour,
                   const PinholeCamera& camera, const SE3& T_world_camera, const IntegrateParams& params,
                   IntegrateStats* stats);

}  // namespace detail

}  // namespace hf::fusion
