#include "fusion/voxel_block_grid.h"

#include <algorithm>
#include <cstddef>
#include <cmath>
#include <mutex>
#include <shared_mutex>
#include <sstream>
#include <unordered_map>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace hf::fusion {

namespace {

constexpr size_t kChunkBlocks = 1024;
constexpr size_t kMaxCapacityBlocks = size_t(1) << 26;

int floor_div8(int v) { return v >= 0 ? v / HF_BLOCK_SIZE : -((-v + HF_BLOCK_SIZE - 1) / HF_BLOCK_SIZE); }

bool coord_less(const BlockCoord& a, const BlockCoord& b) {
  if (a.z != b.z) return a.z < b.z;
  if (a.y != b.y) return a.y < b.y;
  return a.x < b.x;
}

}  // namespace

void VolumeParams::validate() const {
  auto fail = [](const std::string& what) { throw Error("invalid volume parameters: " + what); };
  if (!(voxel_m > 0.0 && voxel_m <= 10.0)) fail("voxel_m must be in (0, 10] metres, got " + std::to_string(voxel_m));
  if (!(truncation_vox >= 1.0 && truncation_vox <= 64.0))
    fail("truncation_vox must be in [1, 64] voxels, got " + std::to_string(truncation_vox));
  if (!(max_weight >= 1.0f && max_weight <= 4095.0f))
    fail("max_weight must be in [1, 4095], got " + std::to_string(max_weight));
  if (capacity_blocks < 1 || capacity_blocks > kMaxCapacityBlocks)
    fail("capacity_blocks must be in [1, 2^26], got " + std::to_string(capacity_blocks));
}

// The pool is a fixed table of chunk pointers (sized from the capacity) so a slot's address never moves and
// readers need no lock to turn a slot into a block pointer; chunks are allocated on first use.
struct VoxelBlockGrid::Impl {
  explicit Impl(size_t capacity)
      : chunks((capacity + kChunkBlocks - 1) / kChunkBlocks), surface_free(chunks.size()) {}

  VoxelBlock* slot_block(std::uint32_t slot) const { return &chunks[slot / kChunkBlocks][slot % kChunkBlocks]; }
  std::uint8_t& slot_surface_free(std::uint32_t slot) const {
    return surface_free[slot / kChunkBlocks][slot % kChunkBlocks];
  }

  mutable std::shared_mutex mutex;
  std::unordered_map<BlockCoord, std::uint32_t, BlockCoordHash> table;
  std::vector<std::unique_ptr<VoxelBlock[]>> chunks;
  std::vector<std::unique_ptr<std::uint8_t[]>> surface_free;  // per slot, beside chunks (see surface_free())
  std::vector<std::uint32_t> free_slots;
  std::uint32_t next_slot = 0;  // slots below this have been handed out at least once
};

VoxelBlockGrid::VoxelBlockGrid(const VolumeParams& params) : params_(params) {
  params_.validate();
  impl_ = std::make_unique<Impl>(params_.capacity_blocks);
}
VoxelBlockGrid::~VoxelBlockGrid() = default;
VoxelBlockGrid::VoxelBlockGrid(VoxelBlockGrid&&) noexcept = default;
VoxelBlockGrid& VoxelBlockGrid::operator=(VoxelBlockGrid&&) noexcept = default;

VoxelBlock* VoxelBlockGrid::find(const BlockCoord& c) {
  std::shared_lock lock(impl_->mutex);
  auto it = impl_->table.find(c);
  return it == impl_->table.end() ? nullptr : impl_->slot_block(it->second);
}

const VoxelBlock* VoxelBlockGrid::find(const BlockCoord& c) const {
  return const_cast<VoxelBlockGrid*>(this)->find(c);
}

VoxelBlock* VoxelBlockGrid::allocate(const BlockCoord& c, bool* created, std::uint8_t** surface_free) {
  if (created) *created = false;
  auto found = [&](std::uint32_t slot) {
    if (surface_free != nullptr) *surface_free = &impl_->slot_surface_free(slot);
    return impl_->slot_block(slot);
  };
  {
    std::shared_lock lock(impl_->mutex);
    auto it = impl_->table.find(c);
    if (it != impl_->table.end()) return found(it->second);
  }
  std::unique_lock lock(impl_->mutex);
  auto it = impl_->table.find(c);  // another thread may have created it between the two locks
  if (it != impl_->table.end()) return found(it->second);
  std::uint32_t slot;
  if (!impl_->free_slots.empty()) {
    slot = impl_->free_slots.back();
    impl_->free_slots.pop_back();
  } else if (impl_->next_slot < params_.capacity_blocks) {
    slot = impl_->next_slot++;
    auto& chunk = impl_->chunks[slot / kChunkBlocks];
    if (!chunk) {
      chunk = std::make_unique<VoxelBlock[]>(kChunkBlocks);  // value-initialised: all voxels zero
      impl_->surface_free[slot / kChunkBlocks] = std::make_unique<std::uint8_t[]>(kChunkBlocks);
    }
  } else {
    std::ostringstream msg;
    msg << "voxel block pool full: capacity " << params_.capacity_blocks << " blocks ("
        << params_.capacity_blocks * sizeof(VoxelBlock) / (1024 * 1024) << " MiB) reached while allocating block ("
        << c.x << ", " << c.y << ", " << c.z << "); raise VolumeParams::capacity_blocks (--capacity-blocks) or "
        << "stream distant blocks out (fusion/streaming.h)";
    throw CapacityError(msg.str());
  }
  VoxelBlock* block = impl_->slot_block(slot);
  block->voxels.fill(Voxel{});
  impl_->slot_surface_free(slot) = 0;
  impl_->table.emplace(c, slot);
  if (created) *created = true;
  if (surface_free != nullptr) *surface_free = &impl_->slot_surface_free(slot);
  return block;
}

bool VoxelBlockGrid::release(const BlockCoord& c) {
  std::unique_lock lock(impl_->mutex);
  auto it = impl_->table.find(c);
  if (it == impl_->table.end()) return false;
  impl_->free_slots.push_back(it->second);
  impl_->table.erase(it);
  return true;
}

void VoxelBlockGrid::clear() {
  std::unique_lock lock(impl_->mutex);
  impl_->table.clear();
  impl_->free_slots.clear();
  impl_->next_slot = 0;
}

size_t VoxelBlockGrid::block_count() const {
  std::shared_lock lock(impl_->mutex);
  return impl_->table.size();
}

size_t VoxelBlockGrid::memory_bytes() const {
  std::shared_lock lock(impl_->mutex);
  // A node of the hash holds the key, the slot and a next pointer (plus the cached hash in libstdc++).
  const size_t node_bytes = sizeof(BlockCoord) + sizeof(std::uint32_t) + 2 * sizeof(void*);
  return impl_->table.size() * (sizeof(VoxelBlock) + node_bytes) + impl_->table.bucket_count() * sizeof(void*);
}

std::vector<BlockCoord> VoxelBlockGrid::block_coords() const {
  std::vector<BlockCoord> coords;
  {
    std::shared_lock lock(impl_->mutex);
    coords.reserve(impl_->table.size());
    for (const auto& [c, slot] : impl_->table) coords.push_back(c);
  }
  std::sort(coords.begin(), coords.end(), coord_less);
  return coords;
}

std::vector<std::pair<BlockCoord, VoxelBlock*>> VoxelBlockGrid::blocks() {
  std::vector<std::pair<BlockCoord, VoxelBlock*>> out;
  {
    std::shared_lock lock(impl_->mutex);
    out.reserve(impl_->table.size());
    for (const auto& [c, slot] : impl_->table) out.emplace_back(c, impl_->slot_block(slot));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return coord_less(a.first, b.first); });
  return out;
}

std::vector<std::pair<BlockCoord, const VoxelBlock*>> VoxelBlockGrid::blocks() const {
  auto mutable_blocks = const_cast<VoxelBlockGrid*>(this)->blocks();
  return {mutable_blocks.begin(), mutable_blocks.end()};
}

std::vector<std::pair<BlockCoord, const VoxelBlock*>> VoxelBlockGrid::blocks_unordered(
    std::vector<std::uint8_t>* surface_free) const {
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> out;
  std::shared_lock lock(impl_->mutex);
  out.reserve(impl_->table.size());
  if (surface_free != nullptr) {
    surface_free->clear();
    surface_free->reserve(impl_->table.size());
  }
  for (const auto& [c, slot] : impl_->table) {
    out.emplace_back(c, impl_->slot_block(slot));
    if (surface_free != nullptr) surface_free->push_back(impl_->slot_surface_free(slot));
  }
  return out;
}

void VoxelBlockGrid::set_surface_free(const BlockCoord& c, bool surface_free) {
  std::shared_lock lock(impl_->mutex);
  auto it = impl_->table.find(c);
  if (it != impl_->table.end()) impl_->slot_surface_free(it->second) = surface_free ? 1 : 0;
}

bool VoxelBlockGrid::surface_free(const BlockCoord& c) const {
  std::shared_lock lock(impl_->mutex);
  auto it = impl_->table.find(c);
  return it != impl_->table.end() && impl_->slot_surface_free(it->second) != 0;
}

bool block_is_surface_free(const VoxelBlock& block) {
  // integrate() asks this of every block it updates, so it must cost far less than the update: branch-free over
  // the 512 voxels. A voxel's low 32 bits are sdf | weight << 16 (little-endian, fusion/kernels/voxel.h); it is on
  // or behind a surface when the word's high half (weight) is not 0 and its low half, as int16, is <= 0.
  static_assert(offsetof(Voxel, sdf) == 0 && offsetof(Voxel, weight) == 2 && sizeof(Voxel) == 8, "voxel layout");
#if defined(__SSE2__)
  const __m128i one = _mm_set1_epi32(1), zero = _mm_setzero_si128();
  __m128i surface = _mm_setzero_si128();
  const auto* p = reinterpret_cast<const __m128i*>(block.voxels.data());
  for (int i = 0; i < HF_VOXELS_PER_BLOCK / 2; i += 2) {
    // Two loads of two voxels each; their low words (lanes 0 and 2) side by side.
    const __m128i a = _mm_loadu_si128(p + i), b = _mm_loadu_si128(p + i + 1);
    const __m128i w =
        _mm_castps_si128(_mm_shuffle_ps(_mm_castsi128_ps(a), _mm_castsi128_ps(b), _MM_SHUFFLE(2, 0, 2, 0)));
    const __m128i sdf = _mm_srai_epi32(_mm_slli_epi32(w, 16), 16);
    const __m128i unobserved = _mm_cmpeq_epi32(_mm_srli_epi32(w, 16), zero);  // weight 0 (unsigned: any weight)
    surface = _mm_or_si128(surface, _mm_andnot_si128(unobserved, _mm_cmplt_epi32(sdf, one)));
  }
  return _mm_movemask_epi8(surface) == 0;
#else
  unsigned surface = 0;
  for (const Voxel& v : block.voxels) surface |= unsigned(v.weight != 0) & unsigned(v.sdf <= 0);
  return surface == 0;
#endif
}

void VoxelBlockGrid::for_each_block(const std::function<void(const BlockCoord&, const VoxelBlock&)>& f) const {
  for (const auto& [c, b] : blocks()) f(c, *b);
}

void VoxelBlockGrid::for_each_block(const std::function<void(const BlockCoord&, VoxelBlock&)>& f) {
  for (const auto& [c, b] : blocks()) f(c, *b);
}

BlockCoord VoxelBlockGrid::block_of(const Eigen::Vector3d& p_world) const {
  const double b = params_.block_m();
  return {int(std::floor(p_world.x() / b)), int(std::floor(p_world.y() / b)), int(std::floor(p_world.z() / b))};
}

Voxel* VoxelBlockGrid::voxel(int i, int j, int k) {
  VoxelBlock* block = find({floor_div8(i), floor_div8(j), floor_div8(k)});
  if (!block) return nullptr;
  return &block->voxels[hf_voxel_index(i - HF_BLOCK_SIZE * floor_div8(i), j - HF_BLOCK_SIZE * floor_div8(j),
                                       k - HF_BLOCK_SIZE * floor_div8(k))];
}

const Voxel* VoxelBlockGrid::voxel(int i, int j, int k) const { return const_cast<VoxelBlockGrid*>(this)->voxel(i, j, k); }

}  // namespace hf::fusion
