#include "fusion/streaming.h"

#include <gtest/gtest.h>

#include <cstring>

#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "fusion/volume_io.h"

namespace hf::fusion {
namespace {

VolumeParams streaming_params_1cm() {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.capacity_blocks = 1 << 15;
  return p;
}

datasets::SyntheticSequence sphere_sequence(int frames) {
  datasets::SyntheticOptions options;
  options.preset = "sphere";
  options.frames = frames;
  options.camera = PinholeCamera::preset("ros").scaled(2);
  return datasets::SyntheticSequence(options);
}

void integrate_frames(VoxelBlockGrid& grid, const datasets::SyntheticSequence& seq, int first, int last,
                      BlockStore* store = nullptr) {
  for (int f = first; f < last; ++f) {
    const auto frame = seq.frame(f);
    integrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera, {}, store);
  }
}

bool same_bytes(const VoxelBlock& a, const VoxelBlock& b) {
  return std::memcmp(a.voxels.data(), b.voxels.data(), sizeof(VoxelBlock)) == 0;
}

TEST(Streaming, OutAndBackIsBitIdentical) {
  const auto seq = sphere_sequence(6);
  VoxelBlockGrid grid(streaming_params_1cm());
  integrate_frames(grid, seq, 0, seq.size());
  const std::string before = serialize_volume(grid);
  const size_t blocks = grid.block_count();
  ASSERT_GT(blocks, 100u);

  // Partial: a camera at +x keeps the near side of the sphere resident.
  BlockStore store;
  const Eigen::Vector3d camera(1.5, 0.0, 0.0);
  const size_t out = stream_out(grid, store, camera, 1.5);
  EXPECT_GT(out, 0u);
  EXPECT_LT(out, blocks);
  EXPECT_EQ(grid.block_count() + store.size(), blocks);
  for (const BlockCoord& c : grid.block_coords()) {
    EXPECT_FALSE(store.contains(c));
    EXPECT_LE((block_centre(grid.params(), c) - camera).norm(), 1.5);
  }
  // The whole map stays visible to a mesher.
  size_t visited = 0;
  for_each_block_including_streamed(grid, store, [&](const BlockCoord& c, const VoxelBlock& b) {
    ++visited;
    EXPECT_EQ(find_block_including_streamed(grid, store, c), &b);
  });
  EXPECT_EQ(visited, blocks);

  // Moving the camera back brings the blocks within the radius in again.
  const size_t in = stream_in(grid, store, Eigen::Vector3d::Zero(), 10.0);
  EXPECT_EQ(in, out);
  EXPECT_TRUE(store.empty());
  EXPECT_EQ(serialize_volume(grid), before);

  // Everything out, everything back.
  EXPECT_EQ(stream_out(grid, store, Eigen::Vector3d(100, 0, 0), 1.0), blocks);
  EXPECT_EQ(grid.block_count(), 0u);
  EXPECT_EQ(stream_in_all(grid, store), blocks);
  EXPECT_EQ(serialize_volume(grid), before);
  // Blocks streamed back get the raycast's per-block flag from their voxels.
  size_t free_blocks = 0;
  for (const auto& [c, b] : grid.blocks()) {
    EXPECT_EQ(grid.surface_free(c), block_is_surface_free(*b));
    free_blocks += grid.surface_free(c) ? 1 : 0;
  }
  EXPECT_GT(free_blocks, 0u);
  EXPECT_LT(free_blocks, blocks);
}

// Integrating with blocks parked in the store gives exactly what integrating without streaming gives: blocks the
// frame touches come back before they are updated, never duplicated as fresh empty blocks.
TEST(Streaming, IntegrateBringsStoredBlocksBack) {
  const auto seq = sphere_sequence(8);
  VoxelBlockGrid reference(streaming_params_1cm());
  integrate_frames(reference, seq, 0, seq.size());

  VoxelBlockGrid grid(streaming_params_1cm());
  BlockStore store;
  integrate_frames(grid, seq, 0, 4);
  const size_t parked = stream_out(grid, store, Eigen::Vector3d(100, 0, 0), 1.0);
  ASSERT_GT(parked, 0u);
  const auto frame = seq.frame(4);
  const IntegrateStats stats = integrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera, {}, &store);
  EXPECT_GT(stats.blocks_streamed_in, 0u);
  for (const BlockCoord& c : grid.block_coords()) EXPECT_FALSE(store.contains(c));
  integrate_frames(grid, seq, 5, seq.size(), &store);
  stream_in_all(grid, store);
  EXPECT_EQ(serialize_volume(grid), serialize_volume(reference));
}

TEST(Streaming, BudgetKeepsNearestBlocks) {
  const auto seq = sphere_sequence(4);
  VoxelBlockGrid grid(streaming_params_1cm());
  integrate_frames(grid, seq, 0, seq.size());
  const size_t blocks = grid.block_count();
  BlockStore store;
  const Eigen::Vector3d camera(0.0, 2.0, 0.0);
  const size_t budget_blocks = blocks / 3;
  EXPECT_EQ(enforce_budget(grid, store, camera, budget_blocks * sizeof(VoxelBlock)), blocks - budget_blocks);
  EXPECT_EQ(grid.block_count(), budget_blocks);
  double farthest_resident = 0, nearest_stored = 1e9;
  for (const BlockCoord& c : grid.block_coords())
    farthest_resident = std::max(farthest_resident, (block_centre(grid.params(), c) - camera).norm());
  for (const BlockCoord& c : store.block_coords())
    nearest_stored = std::min(nearest_stored, (block_centre(grid.params(), c) - camera).norm());
  EXPECT_LE(farthest_resident, nearest_stored);
  EXPECT_EQ(enforce_budget(grid, store, camera, budget_blocks * sizeof(VoxelBlock)), 0u);
  EXPECT_GT(store.memory_bytes(), store.size() * sizeof(VoxelBlock) - 1);
}

TEST(Streaming, StreamInBeyondCapacityThrowsAndKeepsBlocks) {
  VolumeParams p = streaming_params_1cm();
  p.capacity_blocks = 4;
  VoxelBlockGrid grid(p);
  BlockStore store;
  for (int i = 0; i < 6; ++i) {
    VoxelBlock b;
    b.voxels[0].weight = hf_uint16(i + 1);
    store.put({i, 0, 0}, b);
  }
  EXPECT_THROW(stream_in_all(grid, store), CapacityError);
  EXPECT_EQ(grid.block_count() + store.size(), 6u);  // nothing lost
  for (int i = 0; i < 6; ++i) {
    const VoxelBlock* b = find_block_including_streamed(grid, store, {i, 0, 0});
    ASSERT_NE(b, nullptr);
    EXPECT_EQ(b->voxels[0].weight, i + 1);
  }
  VoxelBlock copy;
  copy.voxels[0].weight = 5;
  EXPECT_TRUE(same_bytes(*find_block_including_streamed(grid, store, {4, 0, 0}), copy));
}

}  // namespace
}  // namespace hf::fusion
