#include "fusion/streaming.h"

#include <algorithm>

namespace hf::fusion {

size_t BlockStore::memory_bytes() const {
  const size_t node_bytes = sizeof(BlockCoord) + sizeof(VoxelBlock) + 2 * sizeof(void*);
  return blocks_.size() * node_bytes + blocks_.bucket_count() * sizeof(void*);
}

bool BlockStore::take(const BlockCoord& c, VoxelBlock* out) {
  auto it = blocks_.find(c);
  if (it == blocks_.end()) return false;
  *out = it->second;
  blocks_.erase(it);
  return true;
}

const VoxelBlock* BlockStore::find(const BlockCoord& c) const {
  auto it = blocks_.find(c);
  return it == blocks_.end() ? nullptr : &it->second;
}

std::vector<BlockCoord> BlockStore::block_coords() const {
  std::vector<BlockCoord> coords;
  coords.reserve(blocks_.size());
  for (const auto& [c, b] : blocks_) coords.push_back(c);
  std::sort(coords.begin(), coords.end(), [](const BlockCoord& a, const BlockCoord& b) {
    return a.z != b.z ? a.z < b.z : (a.y != b.y ? a.y < b.y : a.x < b.x);
  });
  return coords;
}

void BlockStore::for_each_block(const std::function<void(const BlockCoord&, const VoxelBlock&)>& f) const {
  for (const auto& c : block_coords()) f(c, blocks_.at(c));
}

Eigen::Vector3d block_centre(const VolumeParams& params, const BlockCoord& c) {
  return (Eigen::Vector3d(c.x, c.y, c.z) + Eigen::Vector3d::Constant(0.5)) * params.block_m();
}

size_t stream_out(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position, double radius_m) {
  size_t moved = 0;
  for (const auto& [c, block] : grid.blocks()) {
    if ((block_centre(grid.params(), c) - camera_position).norm() <= radius_m) continue;
    store.put(c, *block);
    grid.release(c);
    ++moved;
  }
  return moved;
}

namespace {

size_t bring_back(VoxelBlockGrid& grid, BlockStore& store, const std::vector<BlockCoord>& coords) {
  size_t moved = 0;
  for (const auto& c : coords) {
    bool created = false;
    std::uint8_t* surface_free = nullptr;
    VoxelBlock* block = grid.allocate(c, &created, &surface_free);  // throws CapacityError before anything is lost
    if (!created) {
      // Both copies exist only if someone broke the invariant; the resident one is newer: drop the stored one.
      VoxelBlock stale;
      store.take(c, &stale);
      continue;
    }
    store.take(c, block);
    *surface_free = block_is_surface_free(*block) ? 1 : 0;  // the raycast may skip it again at once
    ++moved;
  }
  return moved;
}

}  // namespace

size_t stream_in(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position, double radius_m) {
  std::vector<BlockCoord> near;
  for (const auto& c : store.block_coords())
    if ((block_centre(grid.params(), c) - camera_position).norm() <= radius_m) near.push_back(c);
  return bring_back(grid, store, near);
}

size_t stream_in_all(VoxelBlockGrid& grid, BlockStore& store) { return bring_back(grid, store, store.block_coords()); }

size_t enforce_budget(VoxelBlockGrid& grid, BlockStore& store, const Eigen::Vector3d& camera_position,
                      size_t max_pool_bytes) {
  const size_t max_blocks = max_pool_bytes / sizeof(VoxelBlock);
  auto blocks = grid.blocks();
  if (blocks.size() <= max_blocks) return 0;
  std::vector<std::pair<double, size_t>> by_distance(blocks.size());
  for (size_t i = 0; i < blocks.size(); ++i)
    by_distance[i] = {(block_centre(grid.params(), blocks[i].first) - camera_position).squaredNorm(), i};
  std::sort(by_distance.begin(), by_distance.end(), std::greater<>());
  const size_t excess = blocks.size() - max_blocks;
  for (size_t k = 0; k < excess; ++k) {
    const auto& [c, block] = blocks[by_distance[k].second];
    store.put(c, *block);
    grid.release(c);
  }
  return excess;
}

void for_each_block_including_streamed(const VoxelBlockGrid& grid, const BlockStore& store,
                                       const std::function<void(const BlockCoord&, const VoxelBlock&)>& f) {
  grid.for_each_block(f);
  store.for_each_block(f);
}

const VoxelBlock* find_block_including_streamed(const VoxelBlockGrid& grid, const BlockStore& store,
                                                const BlockCoord& c) {
  if (const VoxelBlock* b = grid.find(c)) return b;
  return store.find(c);
}

}  // namespace hf::fusion
