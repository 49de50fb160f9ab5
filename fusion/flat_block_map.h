// A VoxelBlockGrid's blocks in the flat layout kernels read (fusion/kernels/block_hash.h): one table array and one
// pool array, for a device that reads a host map it does not hold (the sdf registration kernel on the OpenCL
// backend, registration/kernels/sdf_kernel.h) and for tests of the shared look-up.
//
//   fusion::FlatBlockMap flat = fusion::flatten(grid);
//   hf_flat_map view = flat.view();  // fusion/kernels/tsdf_sample.h: hf_tsdf_cell(&view, i, j, k, ...)
//
// The table has bit_ceil(max(16, 2 blocks)) entries (at most half full, as VoxelBlockGrid's), so a look-up stops
// at an empty entry; max_probe is the longest probe run plus one (an exact bound: no key present lies further).
// The pool holds the blocks in the grid's hash order, slot s at pool[s * 512, (s + 1) * 512). Cost: one copy of
// every block (4 KiB each) and a table insert per block.
#pragma once

#include <cstdint>
#include <vector>

#include "fusion/kernels/tsdf_sample.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

struct FlatBlockMap {
  std::vector<hf_block_entry> table;
  std::vector<Voxel> pool;  // never empty: one unobserved block when the grid has none (a buffer for the kernels)
  int shift = 60;           // 64 - log2(table.size())
  int max_probe = 1;
  size_t blocks = 0;

  std::uint32_t mask() const { return std::uint32_t(table.size() - 1); }
  hf_flat_map view() const;
};

// The table size flatten() uses for a grid of `blocks` blocks: bit_ceil(max(16, 2 blocks)).
size_t flat_table_entries(size_t blocks);

// table_entries: 0 for flat_table_entries(blocks), else that size (a power of two of at least
// flat_table_entries(blocks) entries: a caller that sized its kernels' parameters from an earlier block count),
// else hf::Error.
FlatBlockMap flatten(const VoxelBlockGrid& grid, size_t table_entries = 0);

}  // namespace hf::fusion
