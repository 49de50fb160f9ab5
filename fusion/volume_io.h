// Save/load of the whole volume (resident and streamed-out blocks) in a versioned binary format with a checksum.
//
// Format "HFVOLUME" version 1, little-endian:
//   char[8]  "HFVOLUME"
//   u32      version (1)
//   payload:
//     f64 voxel_m, f64 truncation_vox, f32 max_weight, u32 reserved (0), u64 capacity_blocks, u64 block_count
//     block_count records, sorted (z, y, x), each: i32 x, y, z, u32 flags (bit 0: streamed out), then the block's
//       512 voxels as 8 bytes each (i16 sdf, u16 weight, u8 r, g, b, flags), index hf_voxel_index(x, y, z)
//   u64      FNV-1a 64 of the payload bytes
// Voxels are stored as they are in memory, so a save/load round trip is bit-identical.
//
// Errors: a missing file, wrong magic, unknown version, truncated or oversized file, checksum mismatch, invalid
// parameters, duplicate blocks or more resident blocks than the capacity give hf::ParseError
// "FILE: expected ..." (what was expected, what was found); nothing is loaded. Writing is atomic
// (core/atomic_file.h): the old file stays intact when a write fails.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

constexpr std::uint32_t kVolumeFormatVersion = 1;

struct Volume {
  VoxelBlockGrid grid;
  BlockStore store;  // blocks that were streamed out when saved
};

// The file's bytes. store may be nullptr (no streamed-out blocks).
std::string serialize_volume(const VoxelBlockGrid& grid, const BlockStore* store = nullptr);
void save_volume(const std::string& path, const VoxelBlockGrid& grid, const BlockStore* store = nullptr);

// name_for_errors is the file name put in ParseError messages.
Volume parse_volume(std::string_view bytes, const std::string& name_for_errors);
Volume load_volume(const std::string& path);

// FNV-1a 64 (offset basis 14695981039346656037, prime 1099511628211).
std::uint64_t fnv1a64(const void* data, size_t size);

}  // namespace hf::fusion
