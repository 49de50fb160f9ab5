// The sampler every pass over the TSDF shares (raycast, render, meshing a list of blocks): voxel access and
// trilinear SDF / colour / normal samples in continuous voxel coordinates, on a grid (its lock-free find) or on a
// BlockLookup over a list of blocks. Implemented in fusion/raycast.cpp beside the march that is its main user; the
// fast paths are held to the general ones bit for bit (tests/fusion/test_raycast.cpp).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "fusion/block_hash_table.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

// A look-up table over a list of blocks that is not a grid (meshing a given set of blocks, e.g. one read back
// from a stream): the same hash table as VoxelBlockGrid (fusion/block_hash_table.h) and the same questions
// (find, region_occupied). Valid while the blocks it was built from are neither released nor moved. A grid needs
// none of this: VoxelBlockGrid::find is lock-free, and a VolumeSampler reads it directly.
class BlockLookup {
 public:
  BlockLookup() = default;
  // surface_free: one flag per block (same order), or nullptr (no block is skippable). A coordinate listed twice
  // keeps its first block.
  explicit BlockLookup(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks,
                       const std::vector<std::uint8_t>* surface_free = nullptr);

  const VoxelBlock* find(int bx, int by, int bz) const {
    const std::uint32_t v = table_.find(bx, by, bz);
    return v != 0 ? blocks_[v - 1] : nullptr;
  }
  // Also whether a raycast may skip the block (its surface_free flag; false for a missing block).
  const VoxelBlock* find(int bx, int by, int bz, bool* skippable) const {
    const std::uint32_t v = table_.find(bx, by, bz);
    *skippable = v != 0 && skippable_[v - 1] != 0;
    return v != 0 ? blocks_[v - 1] : nullptr;
  }
  size_t size() const { return table_.size(); }
  // VoxelBlockGrid::region_occupied for the listed blocks.
  bool region_occupied(int rx, int ry, int rz) const { return regions_.find(rx, ry, rz) != 0; }

 private:
  BlockHashTable table_;    // coordinate -> index into blocks_ + 1
  BlockHashTable regions_;  // region -> 1
  std::vector<const VoxelBlock*> blocks_;
  std::vector<std::uint8_t> skippable_;
};

// Voxel access and trilinear sampling in continuous voxel coordinates (voxel centres at integers, see
// VoxelBlockGrid::voxel_coords). Caches the last blocks, so neighbouring samples cost no hash lookup, and the last
// trilinear cell's eight values, so samples in the same cell (a march's short steps near the surface, the
// refinement of a crossing) cost no gather. One sampler per thread (not thread-safe itself); many samplers may
// share one grid or BlockLookup. The caches only save work: every result equals the uncached computation bit for bit.
class VolumeSampler {
 public:
  // Voxels with weight < min_weight count as unobserved, as do never-observed voxels (weight 0) always. On a
  // grid, skippable blocks are its surface_free() ones when skip_surface_free (else none); the grid must not be
  // changed while the sampler reads it except by allocate().
  VolumeSampler(const VoxelBlockGrid& grid, float min_weight, bool skip_surface_free = true);
  VolumeSampler(const BlockLookup& lookup, float min_weight);

  // The voxel at world-grid index (i, j, k), or nullptr when its block does not exist.
  const Voxel* voxel(int i, int j, int k) {
    const VoxelBlock* b = block(i >> 3, j >> 3, k >> 3);  // arithmetic shift: floor division by 8
    return b ? &b->voxels[hf_voxel_index(i & 7, j & 7, k & 7)] : nullptr;
  }
  // The block at block coordinates (bx, by, bz) or nullptr. Cached in 8 entries chosen by the parity of the
  // coordinates, so the up to 8 blocks of any 2 x 2 x 2 neighbourhood (a trilinear sample or a gradient across a
  // block border) stay cached together.
  const VoxelBlock* block(int bx, int by, int bz) {
    bool unused;
    return block(bx, by, bz, &unused);
  }
  // The same, and whether a raycast may skip it (BlockLookup::find).
  const VoxelBlock* block(int bx, int by, int bz, bool* skippable) {
    CacheEntry& e = cache_[(bx & 1) | ((by & 1) << 1) | ((bz & 1) << 2)];
    if (bx != e.x || by != e.y || bz != e.z) {
      if (grid_ != nullptr) {
        e.block = grid_->find(BlockCoord{bx, by, bz}, &e.skippable);
        e.skippable = e.skippable && skip_surface_free_;
      } else {
        e.block = lookup_->find(bx, by, bz, &e.skippable);
      }
      e.x = bx, e.y = by, e.z = bz;
    }
    *skippable = e.skippable;
    return e.block;
  }
  // VoxelBlockGrid::region_occupied with the last region cached.
  bool region_occupied(int rx, int ry, int rz) {
    if (rx != rx_ || ry != ry_ || rz != rz_) {
      region_ = grid_ != nullptr ? grid_->region_occupied(rx, ry, rz) : lookup_->region_occupied(rx, ry, rz);
      rx_ = rx, ry_ = ry, rz_ = rz;
    }
    return region_;
  }
  bool observed(const Voxel* v) const { return v != nullptr && v->weight >= min_weight_raw_; }
  // The raw SDF (int16 units: divide by HF_SDF_SCALE) of trilinear cell (i, j, k)'s eight corner voxels (corner
  // c = x + 2 y + 4 z), or nullptr when one is unobserved; the cached gather sdf() uses, valid until the next call.
  const float* cell_corners(int i, int j, int k) { return cell(i, j, k); }

  // Trilinear normalised SDF at p_vox; false when any of the eight voxels is unobserved.
  bool sdf(const Eigen::Vector3f& p_vox, float* sdf);
  // The same plus trilinear colour (0..255 per channel).
  bool sdf_color(const Eigen::Vector3f& p_vox, float* sdf, Eigen::Vector3f* rgb);
  // Unit SDF gradient (pointing into free space) by central differences of trilinear samples h_vox apart; false
  // when a sample is unobserved or the gradient vanishes. For h_vox = 1 the six samples share their fractional
  // offset, so their 48 corners are 32 voxels of the 4 x 4 x 4 neighbourhood of p_vox: those are gathered once
  // (the at most 8 blocks it touches looked up once, no per-voxel branch) instead of six separate trilinear
  // look-ups.
  bool normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox = 1.0f);

  // The general paths the fast ones above replace, kept as their reference (tests/fusion/test_raycast.cpp holds
  // sdf, sdf_color and normal to them bit for bit): every voxel through voxel(), no cell cache, early exits.
  bool sdf_reference(const Eigen::Vector3f& p_vox, float* sdf);
  bool normal_reference(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n);

 private:
  // A missing block reads as this one: all voxels unobserved (weight 0), so gathers need no null checks.
  const VoxelBlock* block_or_empty(int bx, int by, int bz);
  // The 2 x 2 x 2 blocks from (bx, by, bz) (index x + 2 y + 4 z), each distinct one looked up once: cx, cy, cz
  // say whether the neighbourhood reaches the next block along x, y, z (else the entries repeat the lower ones).
  void neighbour_blocks(int bx, int by, int bz, bool cx, bool cy, bool cz, const VoxelBlock* B[8]);
  // The eight corner voxels of cell (i, j, k) (corner c = x + 2 y + 4 z), never nullptr.
  void gather_cell(int i, int j, int k, const Voxel* v[8]);
  // The raw (int16 as float) SDF of cell (i, j, k)'s corners, or nullptr when one is unobserved; cached.
  const float* cell(int i, int j, int k);
  bool corners_reference(const Eigen::Vector3f& p_vox, const Voxel* v[8], float f[3]);
  // Raw (int16 as float) SDF of voxels (i .. i + N - 1, j, k) into out; false when one is unobserved.
  template <int N>
  bool row(int i, int j, int k, float* out);

  const VoxelBlockGrid* grid_ = nullptr;  // one of these two
  const BlockLookup* lookup_ = nullptr;
  bool skip_surface_free_ = false;
  std::uint16_t min_weight_raw_;  // >= 1: weight 0 (never observed) is always unobserved
  struct CacheEntry {
    int x = -2147483647 - 1, y = 0, z = 0;  // nothing cached yet (block x never reaches INT_MIN)
    bool skippable = false;
    const VoxelBlock* block = nullptr;
  };
  CacheEntry cache_[8];
  int rx_ = -2147483647 - 1, ry_ = 0, rz_ = 0;
  bool region_ = false;
  int ci_ = -2147483647 - 1, cj_ = 0, ck_ = 0;  // the cached cell (none yet)
  bool cell_ok_ = false;
  float cell_[8] = {};
};

}  // namespace hf::fusion
