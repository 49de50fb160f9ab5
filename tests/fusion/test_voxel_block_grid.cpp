#include "fusion/voxel_block_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <map>
#include <random>
#include <set>
#include <thread>
#include <tuple>
#include <utility>

#include "fusion/block_hash_table.h"
#include "fusion/gc.h"

namespace hf::fusion {
namespace {

VolumeParams small_params(size_t capacity = 4096) {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.capacity_blocks = capacity;
  return p;
}

TEST(VoxelBlockGrid, AllocateFindAndVoxelIndexing) {
  VoxelBlockGrid grid(small_params());
  EXPECT_EQ(grid.block_count(), 0u);
  EXPECT_EQ(grid.find({0, 0, 0}), nullptr);
  bool created = false;
  VoxelBlock* b = grid.allocate({-1, 2, -3}, &created);
  EXPECT_TRUE(created);
  EXPECT_EQ(grid.allocate({-1, 2, -3}, &created), b);
  EXPECT_FALSE(created);
  EXPECT_EQ(grid.find({-1, 2, -3}), b);
  for (const Voxel& v : b->voxels) EXPECT_EQ(v.weight, 0);
  // World voxel (-8, 16, -24) is voxel (0, 0, 0) of block (-1, 2, -3); (-1, 23, -17) is (7, 7, 7).
  EXPECT_EQ(grid.voxel(-8, 16, -24), &b->voxels[0]);
  EXPECT_EQ(grid.voxel(-1, 23, -17), &b->voxels[hf_voxel_index(7, 7, 7)]);
  EXPECT_EQ(grid.voxel(0, 16, -24), nullptr);
  // block_of and voxel_coords agree with the documented geometry.
  const BlockCoord c = grid.block_of(Eigen::Vector3d(-0.001, 0.16, -0.2399));
  EXPECT_EQ(c, (BlockCoord{-1, 2, -3}));
  EXPECT_TRUE(grid.voxel_coords(Eigen::Vector3d(0.005, 0.015, -0.005)).isApprox(Eigen::Vector3d(0, 1, -1)));
  EXPECT_EQ(grid.memory_bytes() >= sizeof(VoxelBlock), true);
  EXPECT_TRUE(grid.release({-1, 2, -3}));
  EXPECT_FALSE(grid.release({-1, 2, -3}));
  EXPECT_EQ(grid.block_count(), 0u);
}

TEST(VoxelBlockGrid, ValidatesParams) {
  VolumeParams p = small_params();
  p.voxel_m = 0.0;
  EXPECT_THROW(VoxelBlockGrid{p}, Error);
  p = small_params();
  p.truncation_vox = 0.5;
  EXPECT_THROW(VoxelBlockGrid{p}, Error);
  p = small_params();
  p.max_weight = 5000.0f;  // would overflow the uint16 weight
  EXPECT_THROW(VoxelBlockGrid{p}, Error);
  p = small_params(0);
  try {
    VoxelBlockGrid grid(p);
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("capacity_blocks"), std::string::npos) << e.what();
  }
}

TEST(VoxelBlockGrid, QuantisationRoundTrips) {
  EXPECT_EQ(hf_quantise_sdf(1.0f), 32767);
  EXPECT_EQ(hf_quantise_sdf(-1.0f), -32767);
  EXPECT_EQ(hf_quantise_sdf(7.0f), 32767);  // clamped
  EXPECT_EQ(hf_quantise_sdf(0.0f), 0);
  for (float s = -1.0f; s <= 1.0f; s += 0.001f) {
    hf_voxel v{};
    v.sdf = hf_quantise_sdf(s);
    EXPECT_LE(std::abs(hf_voxel_sdf(v) - s), 0.5f / HF_SDF_SCALE + 1e-7f);
  }
  hf_voxel v{};
  v.weight = hf_quantise_weight(128.0f);
  EXPECT_EQ(hf_voxel_weight(v), 128.0f);
  EXPECT_EQ(hf_quantise_weight(1e9f), HF_WEIGHT_MAX_RAW);
  EXPECT_EQ(hf_quantise_weight(-1.0f), 0);
}

// Coordinates whose full hash value is identical: x = a^-1 (H ^ y b ^ z c) mod 2^32 (a is odd, so invertible).
std::vector<BlockCoord> colliding_coords(int n, std::uint32_t H) {
  const std::uint32_t a = 73856093u, b = 19349669u, c = 83492791u;
  std::uint32_t inv = a;  // Newton iteration for the inverse of an odd number mod 2^32
  for (int i = 0; i < 5; ++i) inv *= 2u - a * inv;
  std::vector<BlockCoord> out;
  for (int i = 0; out.size() < size_t(n); ++i) {
    const int y = i % 64 - 32, z = i / 64 - 16;
    const std::uint32_t x = inv * (H ^ (std::uint32_t(y) * b) ^ (std::uint32_t(z) * c));
    out.push_back({int(x), y, z});
  }
  return out;
}

TEST(VoxelBlockGrid, HashStressWithCollidingKeys) {
  const auto coords = colliding_coords(1500, 0xdeadbeefu);
  const BlockCoordHash hash;
  for (const auto& c : coords) ASSERT_EQ(hash(c), hash(coords[0]));
  VoxelBlockGrid grid(small_params());
  std::set<VoxelBlock*> distinct;
  for (size_t i = 0; i < coords.size(); ++i) {
    VoxelBlock* b = grid.allocate(coords[i]);
    b->voxels[0].weight = hf_uint16(i);
    b->voxels[1].weight = hf_uint16(i >> 16);
    distinct.insert(b);
  }
  EXPECT_EQ(distinct.size(), coords.size());
  EXPECT_EQ(grid.block_count(), coords.size());
  // Remove every other one, then every remaining one still finds its own block.
  for (size_t i = 0; i < coords.size(); i += 2) EXPECT_TRUE(grid.release(coords[i]));
  for (size_t i = 0; i < coords.size(); ++i) {
    const VoxelBlock* b = grid.find(coords[i]);
    if (i % 2 == 0) {
      EXPECT_EQ(b, nullptr);
    } else {
      ASSERT_NE(b, nullptr);
      EXPECT_EQ(b->voxels[0].weight, hf_uint16(i));
    }
  }
  // Freed slots are reused, and come back zeroed.
  for (size_t i = 0; i < coords.size(); i += 2) {
    VoxelBlock* b = grid.allocate(coords[i]);
    EXPECT_EQ(b->voxels[0].weight, 0);
  }
  EXPECT_EQ(grid.block_count(), coords.size());
}

// The table under the grid against a std::map model: a table for 24 keys (64 entries) with keys from a small
// range, so probe runs are long and wrap around the array end; random inserts, updates and erasures (backward
// shift) in random order, every key checked after every step.
TEST(BlockHashTable, MatchesAMapThroughInsertsAndBackwardShiftErasures) {
  BlockHashTable table(24);
  EXPECT_EQ(table.max_entries(), 24u);
  EXPECT_EQ(table.bytes(), 64u * 16u);
  std::map<std::tuple<int, int, int>, std::uint32_t> model;
  std::mt19937 rng(11);
  std::uniform_int_distribution<int> coord(-3, 3);
  for (int step = 0; step < 4000; ++step) {
    const int x = coord(rng), y = coord(rng), z = coord(rng);
    const auto key = std::make_tuple(x, y, z);
    const bool present = model.count(key) != 0;
    if (present && rng() % 3 == 0) {
      EXPECT_EQ(table.erase(x, y, z), model[key]);
      model.erase(key);
    } else if (present) {
      const std::uint32_t v = 1 + rng() % 1000;
      EXPECT_TRUE(table.set_value(x, y, z, v));
      model[key] = v;
    } else {
      const std::uint32_t v = 1 + rng() % 1000;
      const bool inserted = table.insert(x, y, z, v);
      EXPECT_EQ(inserted, model.size() < 24u);
      if (inserted) model[key] = v;
    }
    ASSERT_EQ(table.size(), model.size());
    for (int a = -3; a <= 3; ++a)
      for (int b = -3; b <= 3; ++b)
        for (int c = -3; c <= 3; ++c) {
          const auto it = model.find(std::make_tuple(a, b, c));
          ASSERT_EQ(table.find(a, b, c), it == model.end() ? 0u : it->second) << "step " << step;
        }
  }
  EXPECT_EQ(table.erase(9, 9, 9), 0u);
  EXPECT_FALSE(table.set_value(9, 9, 9, 1));
  table.clear();
  EXPECT_EQ(table.size(), 0u);
  EXPECT_EQ(table.find(0, 0, 0), 0u);
}

// Growth: a table starts with room for its initial keys and doubles at load 0.5, so its live array stays within
// [2, 4] entries per key once grown (never more than the capacity asks: room() <= max_entries); keys survive each
// rehash; retired arrays (halving sizes, so less than the live one in all) wait for reclaim(); reserve() grows
// ahead; clear() returns to the initial room.
TEST(BlockHashTable, GrowsByDoublingKeepsEveryKeyAndReclaimsRetiredArrays) {
  BlockHashTable table(100000, 64);
  EXPECT_EQ(table.room(), 64u);
  EXPECT_EQ(table.bytes(), 128u * 16u);
  for (int i = 0; i < 5000; ++i) {
    ASSERT_TRUE(table.insert(i, -i, i / 7, std::uint32_t(i + 1)));
    const size_t entries = table.bytes() / 16;
    ASSERT_GE(entries, 2 * table.size()) << "load above 0.5 after " << i + 1 << " keys";
    if (table.size() > 64) {
      ASSERT_LE(entries, 4 * table.size()) << "grown more than one doubling ahead";
    }
  }
  EXPECT_EQ(table.bytes(), 16384u * 16u);  // 5000 keys: 8192 entries hold 4096, so 16384
  EXPECT_EQ(table.retired_bytes(), (128u + 256 + 512 + 1024 + 2048 + 4096 + 8192) * 16u);
  EXPECT_LT(table.retired_bytes(), table.bytes());
  for (int i = 0; i < 5000; ++i) ASSERT_EQ(table.find(i, -i, i / 7), std::uint32_t(i + 1));
  EXPECT_EQ(table.reclaim(), (128u + 256 + 512 + 1024 + 2048 + 4096 + 8192) * 16u);
  EXPECT_EQ(table.retired_bytes(), 0u);
  table.reserve(20000);
  EXPECT_EQ(table.bytes(), 65536u * 16u);
  for (int i = 0; i < 5000; ++i) ASSERT_EQ(table.find(i, -i, i / 7), std::uint32_t(i + 1));
  table.clear();
  EXPECT_EQ(table.room(), 64u);
  EXPECT_EQ(table.retired_bytes(), 0u);
  EXPECT_EQ(table.find(1, -1, 0), 0u);
  // The capacity caps growth: a table for 100 keys never holds a 101st, nor grows past 256 entries.
  BlockHashTable small(100, 16);
  for (int i = 0; i < 100; ++i) ASSERT_TRUE(small.insert(i, 0, 0, 1));
  EXPECT_FALSE(small.insert(100, 0, 0, 1));
  EXPECT_EQ(small.room(), 100u);
  EXPECT_EQ(small.bytes(), 256u * 16u);
}

// The grid's tables follow the map, not the capacity: a default-capacity grid (131072 blocks) holding 3000 blocks
// reports hash bytes for ~3000 keys (8192 entries for the blocks, the initial 4096 for their 60 regions, 16 bytes
// each), where tables sized to the capacity held 2 x 262144 entries (8 MiB); free_retired_tables() returns what
// growth retired (the blocks' first 4096-entry array).
TEST(VoxelBlockGrid, HashTablesAreSizedToTheMap) {
  VoxelBlockGrid grid(VolumeParams{});
  for (int i = 0; i < 3000; ++i) grid.allocate({i % 20, (i / 20) % 15, i / 300});
  const size_t per_block = sizeof(VoxelBlock) + sizeof(std::uint8_t) + sizeof(BlockCoord);
  const size_t table_bytes = grid.memory_bytes() - 3000 * per_block;
  EXPECT_LE(table_bytes, (8192u + 4096u) * 16u);
  EXPECT_EQ(grid.free_retired_tables(), 4096u * 16u);
  EXPECT_EQ(grid.free_retired_tables(), 0u);
  for (int i = 0; i < 3000; ++i) ASSERT_NE(grid.find({i % 20, (i / 20) % 15, i / 300}), nullptr);
}

// find() needs no lock: readers looking keys up while a writer inserts see each key either absent or with its own
// value (a torn entry would show another key's value), and every key once the writer is done. The table starts
// small, so the readers also probe arrays that growth has retired under them.
TEST(BlockHashTable, ReadersDuringInsertsSeeWholeEntries) {
  constexpr int kKeys = 20000;
  BlockHashTable table(kKeys);
  auto value_of = [](int i) { return std::uint32_t(i) * 2654435761u | 1u; };
  std::atomic<bool> done{false};
  std::atomic<long> wrong{0};
  std::vector<std::thread> readers;
  for (int t = 0; t < 3; ++t)
    readers.emplace_back([&, t] {
      std::mt19937 rng(t);
      while (!done.load()) {
        const int i = int(rng() % kKeys);
        const std::uint32_t v = table.find(i % 31, (i / 31) % 29, i / (31 * 29));
        if (v != 0 && v != value_of(i)) ++wrong;
      }
    });
  for (int i = 0; i < kKeys; ++i) ASSERT_TRUE(table.insert(i % 31, (i / 31) % 29, i / (31 * 29), value_of(i)));
  done = true;
  for (auto& r : readers) r.join();
  EXPECT_EQ(wrong.load(), 0);
  EXPECT_GT(table.retired_bytes(), 0u);  // it grew while they read
  for (int i = 0; i < kKeys; ++i) ASSERT_EQ(table.find(i % 31, (i / 31) % 29, i / (31 * 29)), value_of(i));
}

// region_occupied follows allocate and release: a region (4^3 blocks) reads occupied while any of its blocks
// exists, negative coordinates included (floor division by 4).
TEST(VoxelBlockGrid, RegionOccupancyFollowsItsBlocks) {
  VoxelBlockGrid grid(small_params());
  EXPECT_FALSE(grid.region_occupied(0, 0, 0));
  grid.allocate({5, 0, 0});
  grid.allocate({7, 3, 1});
  grid.allocate({-1, -4, -5});
  EXPECT_TRUE(grid.region_occupied(1, 0, 0));
  EXPECT_TRUE(grid.region_occupied(-1, -1, -2));
  EXPECT_FALSE(grid.region_occupied(0, 0, 0));
  EXPECT_FALSE(grid.region_occupied(-1, -1, -1));
  EXPECT_TRUE(grid.release({5, 0, 0}));
  EXPECT_TRUE(grid.region_occupied(1, 0, 0));  // (7, 3, 1) is still there
  EXPECT_TRUE(grid.release({7, 3, 1}));
  EXPECT_FALSE(grid.region_occupied(1, 0, 0));
  bool surface_free = true;
  EXPECT_EQ(grid.find({5, 0, 0}, &surface_free), nullptr);
  EXPECT_FALSE(surface_free);
  grid.clear();
  EXPECT_FALSE(grid.region_occupied(-1, -1, -2));
  EXPECT_EQ(grid.block_count(), 0u);
}

TEST(VoxelBlockGrid, CapacityExhaustionThrowsTypedError) {
  VoxelBlockGrid grid(small_params(10));
  for (int i = 0; i < 10; ++i) grid.allocate({i, 0, 0});
  EXPECT_NO_THROW(grid.allocate({3, 0, 0}));  // existing blocks are still found
  try {
    grid.allocate({10, 0, 0});
    FAIL() << "expected CapacityError";
  } catch (const CapacityError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("capacity 10 blocks"), std::string::npos) << msg;
    EXPECT_NE(msg.find("capacity_blocks"), std::string::npos) << msg;
  }
  EXPECT_EQ(grid.block_count(), 10u);
  grid.release({0, 0, 0});
  EXPECT_NO_THROW(grid.allocate({10, 0, 0}));
}

TEST(VoxelBlockGrid, ConcurrentAllocationGivesOneBlockPerCoord) {
  VoxelBlockGrid grid(small_params(1 << 14));
  constexpr int kThreads = 8, kCoords = 3000;
  std::vector<std::vector<VoxelBlock*>> seen(kThreads, std::vector<VoxelBlock*>(kCoords));
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      std::vector<int> order(kCoords);
      for (int i = 0; i < kCoords; ++i) order[i] = i;
      std::shuffle(order.begin(), order.end(), std::mt19937(t));
      for (int i : order) seen[t][i] = grid.allocate({i % 20, (i / 20) % 20, i / 400});
    });
  }
  for (auto& th : threads) th.join();
  EXPECT_EQ(grid.block_count(), size_t(kCoords));
  std::set<VoxelBlock*> distinct;
  for (int i = 0; i < kCoords; ++i) {
    for (int t = 1; t < kThreads; ++t) ASSERT_EQ(seen[t][i], seen[0][i]) << "coord " << i;
    distinct.insert(seen[0][i]);
    EXPECT_EQ(grid.find({i % 20, (i / 20) % 20, i / 400}), seen[0][i]);
  }
  EXPECT_EQ(distinct.size(), size_t(kCoords));
}

TEST(VoxelBlockGrid, IterationIsSortedAndComplete) {
  VoxelBlockGrid grid(small_params());
  grid.allocate({1, 0, 0});
  grid.allocate({0, 0, 1});
  grid.allocate({0, 1, 0});
  grid.allocate({-1, 0, 0});
  const auto coords = grid.block_coords();
  ASSERT_EQ(coords.size(), 4u);
  EXPECT_EQ(coords[0], (BlockCoord{-1, 0, 0}));
  EXPECT_EQ(coords[1], (BlockCoord{1, 0, 0}));
  EXPECT_EQ(coords[2], (BlockCoord{0, 1, 0}));
  EXPECT_EQ(coords[3], (BlockCoord{0, 0, 1}));
  std::vector<BlockCoord> visited;
  grid.for_each_block([&](const BlockCoord& c, const VoxelBlock&) { visited.push_back(c); });
  EXPECT_EQ(visited, coords);
  // The unordered snapshot holds the same (coordinate, block) pairs.
  auto unordered = grid.blocks_unordered();
  std::sort(unordered.begin(), unordered.end(), [](const auto& a, const auto& b) {
    return std::tie(a.first.z, a.first.y, a.first.x) < std::tie(b.first.z, b.first.y, b.first.x);
  });
  const auto sorted = std::as_const(grid).blocks();
  ASSERT_EQ(unordered.size(), sorted.size());
  for (size_t i = 0; i < sorted.size(); ++i) {
    EXPECT_EQ(unordered[i].first, sorted[i].first);
    EXPECT_EQ(unordered[i].second, sorted[i].second);
  }
}

// block_is_surface_free: false exactly when an observed voxel (weight > 0) has sdf <= 0; unobserved voxels do
// not count whatever they hold.
TEST(VoxelBlockGrid, BlockIsSurfaceFreeLooksAtObservedVoxelsOnly) {
  VoxelBlock b{};
  EXPECT_TRUE(block_is_surface_free(b));  // never observed
  for (auto& v : b.voxels) v = Voxel{hf_int16(100), hf_uint16(16), 0, 0, 0, 0};
  EXPECT_TRUE(block_is_surface_free(b));  // all in front of a surface
  b.voxels[511].sdf = -32767;
  b.voxels[511].weight = 0;
  EXPECT_TRUE(block_is_surface_free(b));  // negative but unobserved
  b.voxels[511].weight = 1;
  EXPECT_FALSE(block_is_surface_free(b));  // the last voxel counts
  b.voxels[511] = Voxel{hf_int16(100), hf_uint16(16), 0, 0, 0, 0};
  b.voxels[0].sdf = 0;
  EXPECT_FALSE(block_is_surface_free(b));  // zero is on the surface
  b.voxels[0].sdf = 1;
  EXPECT_TRUE(block_is_surface_free(b));
  for (const std::uint16_t w : {std::uint16_t(0x8000), std::uint16_t(0xFFFF)}) {  // weights with the top bit set
    b.voxels[200] = Voxel{hf_int16(-5), w, 0, 0, 0, 0};
    EXPECT_FALSE(block_is_surface_free(b)) << w;
  }
  b.voxels[200] = Voxel{hf_int16(5), hf_uint16(0xFFFF), 255, 255, 255, 255};  // colour bits do not count
  EXPECT_TRUE(block_is_surface_free(b));
}

// The per-block flag: false when allocated (also for a slot reused after release), set and read per coordinate,
// reported by blocks_unordered in its order; a missing block reads false and setting it does nothing.
TEST(VoxelBlockGrid, SurfaceFreeFlagFollowsTheBlock) {
  VoxelBlockGrid grid(small_params());
  const BlockCoord a{0, 0, 0}, b{1, 2, 3}, missing{9, 9, 9};
  grid.allocate(a);
  grid.allocate(b);
  EXPECT_FALSE(grid.surface_free(a));
  grid.set_surface_free(b, true);
  EXPECT_TRUE(grid.surface_free(b));
  EXPECT_FALSE(grid.surface_free(a));
  grid.set_surface_free(missing, true);
  EXPECT_FALSE(grid.surface_free(missing));
  EXPECT_EQ(grid.find(missing), nullptr);
  std::vector<std::uint8_t> flags;
  const auto blocks = grid.blocks_unordered(&flags);
  ASSERT_EQ(flags.size(), blocks.size());
  for (size_t i = 0; i < blocks.size(); ++i) EXPECT_EQ(flags[i] != 0, blocks[i].first == b);
  ASSERT_TRUE(grid.release(b));
  grid.allocate(b);  // reuses the freed slot
  EXPECT_FALSE(grid.surface_free(b));
  // The flag's address from allocate(), for a new and for an existing block, is the flag surface_free() reads.
  for (const BlockCoord& c : {BlockCoord{5, 5, 5}, a}) {
    bool created = false;
    std::uint8_t* flag = nullptr;
    ASSERT_NE(grid.allocate(c, &created, &flag), nullptr);
    EXPECT_EQ(created, c.x == 5);
    ASSERT_NE(flag, nullptr);
    EXPECT_EQ(*flag, 0);
    *flag = 1;
    EXPECT_TRUE(grid.surface_free(c));
  }
}

TEST(GarbageCollect, ReleasesUnobservedAndFreeSpaceBlocksOnly) {
  VoxelBlockGrid grid(small_params());
  grid.allocate({0, 0, 0});  // never observed
  VoxelBlock* free_space = grid.allocate({1, 0, 0});
  for (auto& v : free_space->voxels) v = Voxel{hf_int16(32767), hf_uint16(32), 0, 0, 0, 0};
  free_space->voxels[5].weight = 0;  // unobserved voxels do not keep it alive
  VoxelBlock* surface = grid.allocate({2, 0, 0});
  for (auto& v : surface->voxels) v = Voxel{hf_int16(32767), hf_uint16(32), 0, 0, 0, 0};
  surface->voxels[100].sdf = -1000;  // one voxel near a surface
  VoxelBlock* inside = grid.allocate({3, 0, 0});
  for (auto& v : inside->voxels) v = Voxel{hf_int16(-32767), hf_uint16(32), 0, 0, 0, 0};

  GcParams keep_free;
  keep_free.release_free_space = false;
  EXPECT_TRUE(block_is_empty(*grid.find({0, 0, 0})));
  EXPECT_FALSE(block_is_empty(*free_space, keep_free));
  EXPECT_EQ(garbage_collect(grid), 2u);
  EXPECT_EQ(grid.block_count(), 2u);
  EXPECT_NE(grid.find({2, 0, 0}), nullptr);
  EXPECT_NE(grid.find({3, 0, 0}), nullptr);
  EXPECT_EQ(garbage_collect(grid), 0u);
}

}  // namespace
}  // namespace hf::fusion
