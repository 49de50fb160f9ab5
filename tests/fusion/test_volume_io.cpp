#include "fusion/volume_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

namespace hf::fusion {
namespace {

// A small grid with every voxel field exercised (random bytes), plus streamed-out blocks.
VoxelBlockGrid random_grid(BlockStore* store) {
  VolumeParams p;
  p.voxel_m = 0.005;
  p.truncation_vox = 3.0;
  p.max_weight = 64.0f;
  p.capacity_blocks = 1000;
  VoxelBlockGrid grid(p);
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255);
  for (int i = 0; i < 20; ++i) {
    VoxelBlock block;
    auto* raw = reinterpret_cast<unsigned char*>(block.voxels.data());
    for (size_t k = 0; k < sizeof(VoxelBlock); ++k) raw[k] = static_cast<unsigned char>(byte(rng));
    const BlockCoord c{i - 10, 3 * i, -i};
    if (store && i % 3 == 0) {
      store->put(c, block);
    } else {
      *grid.allocate(c) = block;
    }
  }
  return grid;
}

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".hfvol")).string();
}

void expect_parse_error(const std::string& bytes, const std::string& needle) {
  try {
    parse_volume(bytes, "map.hfvol");
    FAIL() << "expected ParseError containing '" << needle << "'";
  } catch (const ParseError& e) {
    const std::string msg = e.what();
    EXPECT_EQ(msg.rfind("map.hfvol: expected", 0), 0u) << msg;
    EXPECT_NE(msg.find(needle), std::string::npos) << msg;
  }
}

TEST(VolumeIo, RoundTripIsBitIdentical) {
  BlockStore store;
  VoxelBlockGrid grid = random_grid(&store);
  // One block in front of a surface (observed, all positive): the raycast may skip it (see below).
  for (Voxel& v : grid.allocate({50, 50, 50})->voxels) v = Voxel{hf_int16(1000), hf_uint16(16), 1, 2, 3, 1};
  const std::string path = temp_path("roundtrip");
  save_volume(path, grid, &store);
  const Volume loaded = load_volume(path);
  std::filesystem::remove(path);
  EXPECT_EQ(loaded.grid.params().voxel_m, grid.params().voxel_m);
  EXPECT_EQ(loaded.grid.params().truncation_vox, grid.params().truncation_vox);
  EXPECT_EQ(loaded.grid.params().max_weight, grid.params().max_weight);
  EXPECT_EQ(loaded.grid.params().capacity_blocks, grid.params().capacity_blocks);
  EXPECT_EQ(loaded.grid.block_coords(), grid.block_coords());
  EXPECT_EQ(loaded.store.block_coords(), store.block_coords());
  for (const auto& [c, b] : grid.blocks())
    EXPECT_EQ(std::memcmp(loaded.grid.find(c)->voxels.data(), b->voxels.data(), sizeof(VoxelBlock)), 0);
  for (const BlockCoord& c : store.block_coords())
    EXPECT_EQ(std::memcmp(loaded.store.find(c)->voxels.data(), store.find(c)->voxels.data(), sizeof(VoxelBlock)), 0);
  EXPECT_EQ(serialize_volume(loaded.grid, &loaded.store), serialize_volume(grid, &store));
  // The raycast's per-block flag is derived, not stored: loading sets it from the voxels.
  for (const auto& [c, b] : loaded.grid.blocks()) EXPECT_EQ(loaded.grid.surface_free(c), block_is_surface_free(*b));
  EXPECT_TRUE(loaded.grid.surface_free({50, 50, 50}));
  EXPECT_FALSE(loaded.grid.surface_free(grid.blocks().front().first));  // random bytes: a surface somewhere
}

TEST(VolumeIo, EmptyVolumeRoundTrips) {
  VoxelBlockGrid grid(VolumeParams{});
  const Volume loaded = parse_volume(serialize_volume(grid), "empty");
  EXPECT_EQ(loaded.grid.block_count(), 0u);
  EXPECT_TRUE(loaded.store.empty());
}

TEST(VolumeIo, CorruptedOrTruncatedFilesAreParseErrors) {
  BlockStore store;
  const VoxelBlockGrid grid = random_grid(&store);
  const std::string good = serialize_volume(grid, &store);

  std::string flipped = good;
  flipped[good.size() / 2] ^= 0x10;
  expect_parse_error(flipped, "checksum");
  std::string bad_sum = good;
  bad_sum.back() ^= 1;
  expect_parse_error(bad_sum, "checksum");
  expect_parse_error(good.substr(0, good.size() - 100), "truncated");
  expect_parse_error(good.substr(0, 30), "truncated");
  expect_parse_error(good + "x", "trailing");
  expect_parse_error("", "HFVOLUME");
  expect_parse_error("PLY\nformat ascii", "HFVOLUME");
  std::string version = good;
  version[8] = 9;
  expect_parse_error(version, "version 1, got 9");
}

// Files whose checksum is right but whose content is not: rewritten with a fresh checksum.
std::string with_checksum(std::string bytes) {
  const std::uint64_t sum = fnv1a64(bytes.data() + 12, bytes.size() - 12 - 8);
  std::memcpy(bytes.data() + bytes.size() - 8, &sum, 8);
  return bytes;
}

TEST(VolumeIo, InvalidContentWithValidChecksum) {
  VolumeParams p;
  p.capacity_blocks = 2;
  VoxelBlockGrid grid(p);
  grid.allocate({0, 0, 0});
  grid.allocate({1, 0, 0});
  const std::string good = serialize_volume(grid);
  EXPECT_NO_THROW(parse_volume(good, "ok"));
  std::string bad_voxel = good;
  const double zero = 0.0;
  std::memcpy(bad_voxel.data() + 12, &zero, 8);
  expect_parse_error(with_checksum(bad_voxel), "voxel_m");
  std::string duplicate = good;  // second block's coordinate = first's
  const size_t record0 = 12 + 40, record1 = record0 + 16 + sizeof(VoxelBlock);
  std::memcpy(duplicate.data() + record1, duplicate.data() + record0, 12);
  expect_parse_error(with_checksum(duplicate), "appears twice");
  std::string bad_flags = good;
  bad_flags[record0 + 12] = 4;
  expect_parse_error(with_checksum(bad_flags), "flags");
  std::string small_capacity = good;
  const std::uint64_t one = 1;
  std::memcpy(small_capacity.data() + 12 + 24, &one, 8);
  expect_parse_error(with_checksum(small_capacity), "at most capacity_blocks = 1");
}

// Issue 35: a FIFO given as a volume blocked the ifstream's open forever; it is refused before opening.
TEST(VolumeIo, FifoIsRefusedBeforeOpening) {
  const std::string fifo = temp_path("fifo");
  std::filesystem::remove(fifo);
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string message;
  try {
    load_volume(fifo);
  } catch (const ParseError& e) {
    message = e.what();
  }
  std::filesystem::remove(fifo);
  EXPECT_EQ(message, fifo + ": expected a readable hashfusion volume file (cannot read volume file: it is a FIFO, "
                            "not a regular file)");
}

TEST(VolumeIo, MissingFileAndAtomicWrite) {
  try {
    load_volume("/nonexistent/dir/map.hfvol");
    FAIL();
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/map.hfvol"), std::string::npos);
  }
  VoxelBlockGrid grid(VolumeParams{});
  EXPECT_THROW(save_volume("/nonexistent/dir/map.hfvol", grid), Error);
  // Saving over an existing file replaces it whole.
  const std::string path = temp_path("atomic");
  grid.allocate({1, 2, 3});
  save_volume(path, grid);
  grid.allocate({4, 5, 6});
  save_volume(path, grid);
  EXPECT_EQ(load_volume(path).grid.block_count(), 2u);
  std::filesystem::remove(path);
}

// The fuzzer's seeds were written by an independent encoder (Python, from the format description in the header):
// they load, so the documented format and the code agree.
TEST(VolumeIo, SeedCorpusFollowsTheDocumentedFormat) {
  const std::string dir = std::string(HF_SOURCE_DIR) + "/tests/fuzz/corpus/fuzz_volume_io/";
  EXPECT_EQ(load_volume(dir + "empty.hfvol").grid.block_count(), 0u);
  const Volume one = load_volume(dir + "one_block.hfvol");
  ASSERT_EQ(one.grid.block_coords(), (std::vector<BlockCoord>{{1, -2, 3}}));
  const Voxel& v = one.grid.find({1, -2, 3})->voxels[5];  // sdf = 5 * 37 - 32767, weight 5, rgb (5, 15, 35), flags 1
  EXPECT_EQ(v.sdf, 5 * 37 - 32767);
  EXPECT_EQ(v.weight, 5);
  EXPECT_EQ(v.r, 5);
  EXPECT_EQ(v.g, 15);
  EXPECT_EQ(v.b, 35);
  EXPECT_EQ(v.flags, 1);
  const Volume two = load_volume(dir + "resident_and_streamed.hfvol");
  EXPECT_EQ(two.grid.block_count(), 1u);
  EXPECT_TRUE(two.store.contains({-5, 7, 100}));
  EXPECT_EQ(two.grid.params().voxel_m, 0.005);
}

}  // namespace
}  // namespace hf::fusion
