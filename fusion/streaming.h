// Block streaming (Niessner et al. 2013, section 5): blocks farther than a radius from the camera leave the voxel
// pool for a host-side BlockStore and come back when the camera returns, so the pool (the "GPU" part of the
// model) stays bounded while the scene grows. Streaming out and back is lossless: a block's 4096 bytes are moved,
// not re-encoded, so voxels round-trip bit-identically.
//
//   BlockStore store;
//   stream_in(grid, store, camera_position, radius_m);      // before integrating a frame
//   integrate(grid, frame..., &store);                        // brings back any stored block the frame touches
//   stream_out(grid, store, camera_position, radius_m);      // after: park what is far away
//   enforce_budget(grid, store, camera_position, max_bytes);  // optional hard memory budget for the pool
//
// A block is either in the grid or in the store, never both (stream_in/out and integrate keep that invariant).
// Distances are measured from the block centre. Thread-safety: none of these run concurrently with anything else
// touching the same grid or store.
#pragma once

#include <cstddef>
#include <functional>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

// Host store of streamed-out blocks: the raw voxel bytes of each block keyed by its coordinate.
class BlockStore {
 public:
  bool contains(const BlockCoord& c) const { return blocks_.count(c) != 0; }
  size_t size() const { return blocks_.size(); }
  bool empty() const { return blocks_.empty(); }
  size_t memory_bytes() const;
  void clear() { blocks_.clear(); }

  // Stores a copy of `block` under c (replacing what was there).
  void put(const BlockCoord& c, const VoxelBlock& block) { blocks_[c] = block; }
  // Copies the stored block into `out` and removes it from the store; false when absent.
  bool take(const BlockCoord& c, VoxelBlock* out);
  const VoxelBlock* find(const BlockCoord& c) const;

  std::vector<BlockCoord> block_coords() const;  // sorted (z, y, x)
  // Calls f for every stored block, in block_coords() order.
  void for_each_block(const std::function<void(const BlockCoord&, const VoxelBlock&)>& f) const;

 private:
  std::unordered_map<BlockCoord, VoxelBlock, BlockCoordHash> blocks_;
};

// Centre of block c in the world frame, metres.
Eigen::Vector3d block_centre(const VolumeParams& params, const BlockCoord& c);

// Moves every grid block whose centre is farther than radius_m from camera_position into the store. Returns the
// number moved.
size_t stream_out(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position, double radius_m);
// Moves every stored block whose centre is within radius_m of camera_position back into the grid. Returns the
// number moved. Throws CapacityError when the pool cannot hold them (the blocks not yet moved stay stored).
size_t stream_in(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position, double radius_m);
// Moves grid blocks into the store, farthest from camera_position first, until the grid holds at most
// max_pool_bytes / sizeof(VoxelBlock) blocks. Returns the number moved.
size_t enforce_budget(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position,
                      size_t max_pool_bytes);
// Brings every stored block back (e.g. before meshing the whole map when the pool is large enough). Throws
// CapacityError like stream_in.
size_t stream_in_all(VoxelBlockGrid& grid, BlockStore& store);

// Visits every block of the map, resident or streamed out: grid blocks first (block_coords() order), then stored
// ones. For meshers and exporters that should see the whole map without growing the pool.
void for_each_block_including_streamed(const VoxelBlockGrid& grid, const BlockStore& store,
                                       const std::function<void(const BlockCoord&, const VoxelBlock&)>& f);
// The block at c wherever it lives (grid first, then store), or nullptr.
const VoxelBlock* find_block_including_streamed(const VoxelBlockGrid& grid, const BlockStore& store,
                                                const BlockCoord& c);

}  // namespace hf::fusion
