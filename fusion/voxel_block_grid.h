// The sparse volume: 8x8x8 voxel blocks in a spatial hash keyed by integer block coordinates (Niessner et al. 2013).
//
// Geometry: voxel (i, j, k) of the world grid has its centre at ((i, j, k) + 0.5) * voxel_m in the world frame;
// block (bx, by, bz) holds the voxels i in [8 bx, 8 bx + 8), likewise j, k. Only blocks near observed surfaces
// exist ("model only what a scene needs"); a voxel of a missing block is "unobserved" (weight 0).
//
// Memory: blocks live in a pool of at most `capacity_blocks` VoxelBlocks, handed out in chunks of 1024 blocks as
// they are needed (so memory follows the blocks in use, not the capacity); a hash table maps a BlockCoord to its
// pool slot and a second one counts the blocks per region (fusion/block_hash_table.h: 16-byte entries, at least
// twice the keys held, grown by doubling as the map grows, up to the capacity). When the pool is full,
// allocate() throws CapacityError (typed, loud; the message says the capacity and how to raise it): never a
// silent stop (InfiniTAM's failure mode). Streaming (fusion/streaming.h) moves distant blocks out of the pool to
// make room.
//
// Thread-safety: find(), region_occupied() and voxel reads take no lock (fusion/block_hash_table.h), so a raycast or
// a volume tracker reads the grid itself, millions of look-ups a frame, with no second table; they may run
// concurrently with each other and with allocate() (a block appears whole: published after its voxels are
// cleared). allocate() is thread-safe against other allocate() calls (each coordinate gets exactly one block
// however many threads ask; creating one takes a mutex, finding one does not); block pointers stay valid until
// that block is released or the grid cleared; writing voxels of distinct blocks from different threads is safe;
// release() and clear() need exclusive access. The grid is move-only.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "core/error.h"
#include "fusion/kernels/voxel.h"

namespace hf::fusion {

using Voxel = hf_voxel;
static_assert(sizeof(Voxel) == 8, "8 bytes per voxel with colour");

struct VoxelBlock {
  std::array<Voxel, HF_VOXELS_PER_BLOCK> voxels{};  // index hf_voxel_index(x, y, z)
};

struct BlockCoord {
  int x = 0, y = 0, z = 0;
  bool operator==(const BlockCoord&) const = default;
};

// Block order by z, then y, then x: the order saved maps and meshes list blocks in (deterministic output).
inline bool block_coord_less(const BlockCoord& a, const BlockCoord& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

struct BlockCoordHash {
  // Niessner's hash: (x * 73856093) ^ (y * 19349669) ^ (z * 83492791), on unsigned to avoid overflow UB.
  size_t operator()(const BlockCoord& c) const {
    return size_t((std::uint32_t(c.x) * 73856093u) ^ (std::uint32_t(c.y) * 19349669u) ^ (std::uint32_t(c.z) * 83492791u));
  }
};

// The voxel pool is full and nothing can be evicted.
class CapacityError : public Error {
 public:
  using Error::Error;
};

struct VolumeParams {
  double voxel_m = 0.01;           // voxel edge length
  double truncation_vox = 4.0;     // mu = truncation_vox * voxel_m
  float max_weight = 128.0f;       // running-average weight cap (lets the model follow slow changes)
  size_t capacity_blocks = 1 << 17;  // pool size: 131072 blocks = 512 MiB at 4 KiB per block (1 .. 2^26)
  double truncation_m() const { return truncation_vox * voxel_m; }
  double block_m() const { return HF_BLOCK_SIZE * voxel_m; }
  // Throws hf::Error naming the bad field: voxel_m in [1e-4, 10], truncation_vox in [1, 64] (at least one voxel
  // so a zero crossing is always sampled; at most 8 blocks), max_weight in [1, 4095] (fits the uint16 weight),
  // capacity_blocks in [1, 2^26].
  void validate() const;
};

class VoxelBlockGrid {
 public:
  explicit VoxelBlockGrid(const VolumeParams& params);  // validates params
  ~VoxelBlockGrid();
  VoxelBlockGrid(VoxelBlockGrid&&) noexcept;
  VoxelBlockGrid& operator=(VoxelBlockGrid&&) noexcept;
  VoxelBlockGrid(const VoxelBlockGrid&) = delete;
  VoxelBlockGrid& operator=(const VoxelBlockGrid&) = delete;

  const VolumeParams& params() const { return params_; }

  // nullptr when the block does not exist. Lock-free.
  VoxelBlock* find(const BlockCoord& c);
  const VoxelBlock* find(const BlockCoord& c) const;
  // The same, and the block's surface_free() flag (false for a missing block): what a raycast asks per block.
  const VoxelBlock* find(const BlockCoord& c, bool* surface_free) const;

  // Coarse occupancy for skipping empty space: a region is kRegionBlocks^3 blocks (region r holds blocks
  // [4 r, 4 r + 4) on each axis); true when any of its blocks exists. Lock-free; kept up to date by allocate()
  // and release().
  static constexpr int kRegionShift = 2;
  static constexpr int kRegionBlocks = 1 << kRegionShift;
  bool region_occupied(int rx, int ry, int rz) const;
  // Returns the existing block or a new one with all voxels zero (unobserved). Thread-safe. Throws CapacityError.
  // With created, also whether the block was created by this call; with surface_free, where the block's
  // surface_free flag lives (valid while the block is), for a caller that sets it without another hash look-up
  // (integrate(), loading, streaming back).
  VoxelBlock* allocate(const BlockCoord& c, bool* created = nullptr, std::uint8_t** surface_free = nullptr);
  // Frees a block (its slot returns to the pool; its memory is kept for reuse). Returns false when it did not
  // exist. Not thread-safe.
  bool release(const BlockCoord& c);
  void clear();

  // Frees the hash arrays that growth retired (fusion/block_hash_table.h). Exclusive: no lock-free reader (find,
  // region_occupied, voxel reads) may run concurrently. integrate() calls it first (it needs the grid to itself
  // anyway), so a map that is fused keeps at most one frame's retired arrays. Returns the bytes freed.
  size_t free_retired_tables();

  size_t block_count() const;
  size_t capacity_blocks() const { return params_.capacity_blocks; }
  // Bytes held by allocated blocks (block_count() * sizeof(VoxelBlock)) and by the hash entries (the live arrays:
  // sized to the blocks held, so this follows the map rather than the capacity).
  size_t memory_bytes() const;

  // Calls f(coord, block) for every allocated block, in block_coords() order (deterministic). f must not
  // allocate or release blocks.
  void for_each_block(const std::function<void(const BlockCoord&, const VoxelBlock&)>& f) const;
  void for_each_block(const std::function<void(const BlockCoord&, VoxelBlock&)>& f);
  std::vector<BlockCoord> block_coords() const;  // sorted (z, y, x)

  // (coord, block) of every allocated block in block_coords() order: for parallel loops over blocks.
  std::vector<std::pair<BlockCoord, VoxelBlock*>> blocks();
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> blocks() const;
  // The same in the hash table's order, without the sort (a 20 k-block map spent ~2 % of the SLAM pipeline's time
  // sorting for each raycast): only for passes whose result does not depend on the order (look-up tables, bounds).
  // With surface_free, also each block's surface_free() flag (same order).
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> blocks_unordered(
      std::vector<std::uint8_t>* surface_free = nullptr) const;

  // Per block, a flag a raycast may skip the block by: true only when no observed voxel of it (weight > 0) has
  // sdf <= 0, so every trilinear sample whose eight corners lie in the block is positive or unobserved and no
  // surface crosses its interior (fusion/raycast.h). integrate() sets it for every block it updates
  // (block_is_surface_free of the result), as do loading a volume and streaming a block back; allocate() starts
  // every block at false (never skip), which stays correct whatever is written into it. Code that writes voxels
  // of a block whose flag is set must clear it (set_surface_free(c, false)) or set it from block_is_surface_free.
  // Setting the flag of a missing block does nothing; a missing block reads false. Thread-safe like voxel writes:
  // distinct blocks from distinct threads, not concurrently with readers of the same block's flag.
  void set_surface_free(const BlockCoord& c, bool surface_free);
  bool surface_free(const BlockCoord& c) const;

  // World point -> block containing it; world point -> continuous voxel coordinates (voxel centres at integers).
  BlockCoord block_of(const Eigen::Vector3d& p_world) const;
  Eigen::Vector3d voxel_coords(const Eigen::Vector3d& p_world) const { return p_world / params_.voxel_m - Eigen::Vector3d::Constant(0.5); }
  // The voxel at integer world-grid index (i, j, k), or nullptr when its block does not exist.
  const Voxel* voxel(int i, int j, int k) const;
  Voxel* voxel(int i, int j, int k);

 private:
  VolumeParams params_;
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// What VoxelBlockGrid::set_surface_free wants to know of a block: no voxel is observed with sdf <= 0.
bool block_is_surface_free(const VoxelBlock& block);

}  // namespace hf::fusion
