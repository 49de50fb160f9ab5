#include "fusion/gc.h"

#include <tbb/parallel_for.h>

#include <vector>

namespace hf::fusion {

bool block_is_empty(const VoxelBlock& block, const GcParams& params) {
  bool any_observed = false;
  bool all_free = true;
  for (const Voxel& v : block.voxels) {
    if (v.weight == 0) continue;
    any_observed = true;
    if (v.sdf != hf_int16(HF_SDF_SCALE)) {
      all_free = false;
      break;
    }
  }
  if (!any_observed) return params.release_unobserved;
  return all_free && params.release_free_space;
}

size_t garbage_collect(VoxelBlockGrid& grid, const GcParams& params) {
  const auto blocks = grid.blocks();
  std::vector<char> empty(blocks.size(), 0);
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t i) { empty[i] = block_is_empty(*blocks[i].second, params); });
  size_t released = 0;
  for (size_t i = 0; i < blocks.size(); ++i)
    if (empty[i] && grid.release(blocks[i].first)) ++released;
  return released;
}

}  // namespace hf::fusion
