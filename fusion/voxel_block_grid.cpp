#include "fusion/voxel_block_grid.h"

#include <algorithm>
#include <climits>
#include <cstddef>
#include <cmath>
#include <mutex>
#include <sstream>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/number_text.h"
#include "fusion/block_hash_table.h"

namespace hf::fusion {

namespace {

constexpr size_t kChunkBlocks = 1024;
constexpr size_t kMaxCapacityBlocks = size_t(1) << 26;

int floor_div8(int v) { return v >= 0 ? v / HF_BLOCK_SIZE : -((-v + HF_BLOCK_SIZE - 1) / HF_BLOCK_SIZE); }

}  // namespace

namespace {
// The finest voxel accepted: 0.1 mm, beyond any depth sensor's resolution.
constexpr double kMinVoxelM = 1e-4;
}  // namespace

void VolumeParams::validate() const {
  auto fail = [](const std::string& what) { throw Error("invalid volume parameters: " + what); };
  // Below 0.1 mm no sensor resolves anything and a room needs more blocks than any pool holds: every frame would be
  // lost to a full pool without a word on why.
  if (!(voxel_m >= kMinVoxelM && voxel_m <= 10.0))
    fail("voxel_m must be in [0.0001, 10] metres, got " + number_for_message(voxel_m));
  if (!(truncation_vox >= 1.0 && truncation_vox <= 64.0))
    fail("truncation_vox must be in [1, 64] voxels, got " + number_for_message(truncation_vox));
  if (!(max_weight >= 1.0f && max_weight <= 4095.0f))
    fail("max_weight must be in [1, 4095], got " + number_for_message(max_weight));
  if (capacity_blocks < 1 || capacity_blocks > kMaxCapacityBlocks)
    fail("capacity_blocks must be in [1, 2^26], got " + std::to_string(capacity_blocks));
}

// The pool is a fixed table of chunk pointers (sized from the capacity) so a slot's address never moves and
// readers need no lock to turn a slot into a block pointer; chunks are allocated on first use. The block table maps
// a coordinate to slot + 1; the region table maps a region (VoxelBlockGrid::kRegionShift) to its number of blocks.
// Both are BlockHashTables: readers never lock; writers (allocate) serialise on create_mutex.
struct VoxelBlockGrid::Impl {
  explicit Impl(size_t capacity)
      : chunks((capacity + kChunkBlocks - 1) / kChunkBlocks),
        surface_free(chunks.size()),
        slot_coords(chunks.size()),
        table(capacity),
        regions(capacity) {}

  VoxelBlock* slot_block(std::uint32_t slot) const { return &chunks[slot / kChunkBlocks][slot % kChunkBlocks]; }
  std::uint8_t& slot_surface_free(std::uint32_t slot) const {
    return surface_free[slot / kChunkBlocks][slot % kChunkBlocks];
  }
  BlockCoord& slot_coord(std::uint32_t slot) const { return slot_coords[slot / kChunkBlocks][slot % kChunkBlocks]; }
  // The slot of block c, or UINT32_MAX. Lock-free.
  std::uint32_t slot_of(const BlockCoord& c) const { return table.find(c.x, c.y, c.z) - 1u; }
  // f(slot) for every allocated block in slot order (create_mutex held by the caller).
  template <class F>
  void for_each_slot(F&& f) const {
    for (std::uint32_t s = 0; s < next_slot; ++s)
      if (slot_live(s)) f(s);
  }
  // A released slot's coordinate reads kFreeSlot (release() marks it), so listings need no hash look-up per slot.
  bool slot_live(std::uint32_t s) const { return slot_coord(s).x != kFreeSlot; }
  static constexpr int kFreeSlot = INT_MIN;

  std::mutex create_mutex;  // serialises allocate()'s writers; taken by the whole-grid listings too
  std::vector<std::unique_ptr<VoxelBlock[]>> chunks;
  std::vector<std::unique_ptr<std::uint8_t[]>> surface_free;  // per slot, beside chunks (see surface_free())
  std::vector<std::unique_ptr<BlockCoord[]>> slot_coords;     // per slot: the block it holds (when live)
  BlockHashTable table;
  BlockHashTable regions;
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
  const std::uint32_t slot = impl_->slot_of(c);
  return slot == UINT32_MAX ? nullptr : impl_->slot_block(slot);
}

const VoxelBlock* VoxelBlockGrid::find(const BlockCoord& c) const {
  return const_cast<VoxelBlockGrid*>(this)->find(c);
}

const VoxelBlock* VoxelBlockGrid::find(const BlockCoord& c, bool* surface_free) const {
  const std::uint32_t slot = impl_->slot_of(c);
  if (slot == UINT32_MAX) {
    *surface_free = false;
    return nullptr;
  }
  *surface_free = impl_->slot_surface_free(slot) != 0;
  return impl_->slot_block(slot);
}

bool VoxelBlockGrid::region_occupied(int rx, int ry, int rz) const { return impl_->regions.find(rx, ry, rz) != 0; }

VoxelBlock* VoxelBlockGrid::allocate(const BlockCoord& c, bool* created, std::uint8_t** surface_free) {
  if (created) *created = false;
  auto found = [&](std::uint32_t slot) {
    if (surface_free != nullptr) *surface_free = &impl_->slot_surface_free(slot);
    return impl_->slot_block(slot);
  };
  if (const std::uint32_t slot = impl_->slot_of(c); slot != UINT32_MAX) return found(slot);
  if (c.x == Impl::kFreeSlot) throw Error("voxel block grid: block x coordinate INT_MIN is out of range");
  std::lock_guard lock(impl_->create_mutex);
  // Another thread may have created it since the look-up above.
  if (const std::uint32_t slot = impl_->slot_of(c); slot != UINT32_MAX) return found(slot);
  std::uint32_t slot;
  if (!impl_->free_slots.empty()) {
    slot = impl_->free_slots.back();
    impl_->free_slots.pop_back();
  } else if (impl_->next_slot < params_.capacity_blocks) {
    slot = impl_->next_slot++;
    const size_t chunk = slot / kChunkBlocks;
    if (!impl_->chunks[chunk]) {
      impl_->chunks[chunk] = std::make_unique<VoxelBlock[]>(kChunkBlocks);  // value-initialised: all voxels zero
      impl_->surface_free[chunk] = std::make_unique<std::uint8_t[]>(kChunkBlocks);
      impl_->slot_coords[chunk] = std::make_unique<BlockCoord[]>(kChunkBlocks);
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
  impl_->slot_coord(slot) = c;
  // The region first, then the block (published last, with its voxels cleared): a reader may see an occupied
  // region whose block is not there yet, never a block of a region that reads empty.
  const int rx = c.x >> kRegionShift, ry = c.y >> kRegionShift, rz = c.z >> kRegionShift;
  if (const std::uint32_t n = impl_->regions.find(rx, ry, rz); n != 0)
    impl_->regions.set_value(rx, ry, rz, n + 1);
  else
    impl_->regions.insert(rx, ry, rz, 1);  // cannot be full: regions <= blocks <= capacity
  impl_->table.insert(c.x, c.y, c.z, slot + 1);
  if (created) *created = true;
  if (surface_free != nullptr) *surface_free = &impl_->slot_surface_free(slot);
  return block;
}

bool VoxelBlockGrid::release(const BlockCoord& c) {
  const std::uint32_t value = impl_->table.erase(c.x, c.y, c.z);
  if (value == 0) return false;
  impl_->free_slots.push_back(value - 1);
  impl_->slot_coord(value - 1).x = Impl::kFreeSlot;
  const int rx = c.x >> kRegionShift, ry = c.y >> kRegionShift, rz = c.z >> kRegionShift;
  const std::uint32_t n = impl_->regions.find(rx, ry, rz);
  if (n > 1)
    impl_->regions.set_value(rx, ry, rz, n - 1);
  else
    impl_->regions.erase(rx, ry, rz);
  return true;
}

void VoxelBlockGrid::clear() {
  impl_->table.clear();
  impl_->regions.clear();
  impl_->free_slots.clear();
  impl_->next_slot = 0;
}

size_t VoxelBlockGrid::free_retired_tables() { return impl_->table.reclaim() + impl_->regions.reclaim(); }

size_t VoxelBlockGrid::block_count() const { return impl_->table.size(); }

size_t VoxelBlockGrid::memory_bytes() const {
  // Blocks in use, their per-slot flag and coordinate, and the two hash tables' live arrays (sized to the map, at
  // load 0.25 to 0.5 once grown).
  return block_count() * (sizeof(VoxelBlock) + sizeof(std::uint8_t) + sizeof(BlockCoord)) + impl_->table.bytes() +
         impl_->regions.bytes();
}

std::vector<BlockCoord> VoxelBlockGrid::block_coords() const {
  std::vector<BlockCoord> coords;
  {
    std::lock_guard lock(impl_->create_mutex);
    coords.reserve(block_count());
    impl_->for_each_slot([&](std::uint32_t s) { coords.push_back(impl_->slot_coord(s)); });
  }
  std::sort(coords.begin(), coords.end(), block_coord_less);
  return coords;
}

std::vector<std::pair<BlockCoord, VoxelBlock*>> VoxelBlockGrid::blocks() {
  std::vector<std::pair<BlockCoord, VoxelBlock*>> out;
  {
    std::lock_guard lock(impl_->create_mutex);
    out.reserve(block_count());
    impl_->for_each_slot([&](std::uint32_t s) { out.emplace_back(impl_->slot_coord(s), impl_->slot_block(s)); });
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return block_coord_less(a.first, b.first); });
  return out;
}

std::vector<std::pair<BlockCoord, const VoxelBlock*>> VoxelBlockGrid::blocks() const {
  auto mutable_blocks = const_cast<VoxelBlockGrid*>(this)->blocks();
  return {mutable_blocks.begin(), mutable_blocks.end()};
}

std::vector<std::pair<BlockCoord, const VoxelBlock*>> VoxelBlockGrid::blocks_unordered(
    std::vector<std::uint8_t>* surface_free) const {
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> out;
  std::lock_guard lock(impl_->create_mutex);
  out.reserve(block_count());
  if (surface_free != nullptr) {
    surface_free->clear();
    surface_free->reserve(block_count());
  }
  impl_->for_each_slot([&](std::uint32_t s) {
    out.emplace_back(impl_->slot_coord(s), impl_->slot_block(s));
    if (surface_free != nullptr) surface_free->push_back(impl_->slot_surface_free(s));
  });
  return out;
}

void VoxelBlockGrid::set_surface_free(const BlockCoord& c, bool surface_free) {
  const std::uint32_t slot = impl_->slot_of(c);
  if (slot != UINT32_MAX) impl_->slot_surface_free(slot) = surface_free ? 1 : 0;
}

bool VoxelBlockGrid::surface_free(const BlockCoord& c) const {
  const std::uint32_t slot = impl_->slot_of(c);
  return slot != UINT32_MAX && impl_->slot_surface_free(slot) != 0;
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
