#include "fusion/deintegrate.h"

#include <tbb/parallel_for.h>

#include <chrono>
#include <cstdint>
#include <utility>
#include <vector>

#include "fusion/gc.h"
#include "core/timing.h"

namespace hf::fusion {

namespace {

}  // namespace

DeintegrateStats deintegrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                             const PinholeCamera& camera, const SE3& T_world_camera, const IntegrateParams& params,
                             BlockStore* store) {
  detail::check_frame_sizes(depth, colour, camera);
  DeintegrateStats stats;
  const VolumeParams& volume = grid.params();

  // The frame's blocks, as integrate() found them; only those that still exist (streamed-out ones come back).
  auto t0 = std::chrono::steady_clock::now();
  const std::vector<BlockCoord> touched = blocks_touched_by(volume, depth, camera, T_world_camera, params);
  std::vector<std::pair<BlockCoord, VoxelBlock*>> found;
  std::vector<std::uint8_t*> surface_free;
  for (const BlockCoord& c : touched) {
    const bool in_store = store != nullptr && store->contains(c);
    if (grid.find(c) == nullptr && !in_store) continue;
    bool created = false;
    std::uint8_t* flag = nullptr;
    VoxelBlock* block = grid.allocate(c, &created, &flag);
    if (created && in_store && store->take(c, block)) ++stats.blocks_streamed_in;
    found.emplace_back(c, block);
    surface_free.push_back(flag);
  }
  stats.blocks_found = found.size();
  stats.find_ms = ms_since(t0);

  IntegrateStats update;
  detail::update_blocks(detail::VoxelUpdate::deintegrate, volume, found, surface_free, depth, colour, camera,
                        T_world_camera, params, &update);
  stats.blocks_visible = update.blocks_visible;
  stats.voxels_updated = update.voxels_updated;
  stats.update_ms = update.update_ms;
  stats.incidence_ms = update.incidence_ms;

  // Garbage collection of what the frame emptied (and of blocks it had allocated but never observed).
  t0 = std::chrono::steady_clock::now();
  GcParams unobserved_only;
  unobserved_only.release_free_space = false;
  std::vector<char> empty(found.size(), 0);
  tbb::parallel_for(size_t(0), found.size(),
                    [&](size_t i) { empty[i] = block_is_empty(*found[i].second, unobserved_only) ? 1 : 0; });
  for (size_t i = 0; i < found.size(); ++i)
    if (empty[i] && grid.release(found[i].first)) ++stats.blocks_released;
  stats.release_ms = ms_since(t0);
  stats.blocks_total = grid.block_count();
  return stats;
}

ReintegrateStats reintegrate(VoxelBlockGrid& grid, const DepthImage& depth, const ColorImage& colour,
                             const PinholeCamera& camera, const SE3& T_world_camera_fused,
                             const SE3& T_world_camera_new, const IntegrateParams& params, BlockStore* store) {
  ReintegrateStats stats;
  stats.deintegrated = deintegrate(grid, depth, colour, camera, T_world_camera_fused, params, store);
  stats.integrated = integrate(grid, depth, colour, camera, T_world_camera_new, params, store);
  return stats;
}

}  // namespace hf::fusion
