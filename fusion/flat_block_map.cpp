#include "fusion/flat_block_map.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

#include "core/error.h"

namespace hf::fusion {

hf_flat_map FlatBlockMap::view() const {
  hf_flat_map m;
  m.table = table.data();
  m.pool = pool.data();
  m.mask = mask();
  m.shift = shift;
  m.max_probe = max_probe;
  return m;
}

size_t flat_table_entries(size_t blocks) { return std::bit_ceil(std::max<size_t>(16, 2 * blocks)); }

FlatBlockMap flatten(const VoxelBlockGrid& grid, size_t table_entries) {
  const auto blocks = grid.blocks_unordered();
  FlatBlockMap flat;
  const size_t needed = flat_table_entries(blocks.size());
  const size_t entries = table_entries == 0 ? needed : table_entries;
  if (entries < needed || !std::has_single_bit(entries))
    throw Error("flatten: a table of " + std::to_string(entries) + " entries for " + std::to_string(blocks.size()) +
                " blocks (needs a power of two >= " + std::to_string(needed) +
                "; did the grid grow since it was sized?)");
  flat.table.assign(entries, hf_block_entry{0, 0, 0, 0});
  flat.shift = 64 - std::countr_zero(entries);
  flat.blocks = blocks.size();
  flat.pool.resize(std::max<size_t>(1, blocks.size()) * HF_VOXELS_PER_BLOCK);
  const std::uint32_t mask = flat.mask();
  int longest = 0;
  for (size_t slot = 0; slot < blocks.size(); ++slot) {
    const BlockCoord& c = blocks[slot].first;
    std::uint32_t e = hf_block_home(c.x, c.y, c.z, flat.shift);
    int probe = 0;
    while (flat.table[e].value != 0) e = (e + 1) & mask, ++probe;  // at most half full: ends
    longest = std::max(longest, probe);
    flat.table[e] = hf_block_entry{c.x, c.y, c.z, std::uint32_t(slot + 1)};
    std::memcpy(flat.pool.data() + slot * HF_VOXELS_PER_BLOCK, blocks[slot].second->voxels.data(),
                sizeof(VoxelBlock));
  }
  flat.max_probe = longest + 1;
  return flat;
}

}  // namespace hf::fusion
