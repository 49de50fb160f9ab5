#include "fusion/block_hash_table.h"

#include <algorithm>
#include <cstring>
#include <new>
#include <utility>

namespace hf::fusion {

BlockHashTable::BlockHashTable(size_t max_entries) : max_entries_(max_entries) {
  const size_t n = std::bit_ceil(std::max<size_t>(16, 2 * max_entries));
  entries_.reset(static_cast<Entry*>(std::calloc(n, sizeof(Entry))));
  if (entries_ == nullptr) throw std::bad_alloc();
  mask_ = n - 1;
  shift_ = 64 - std::countr_zero(n);
}

BlockHashTable::BlockHashTable(BlockHashTable&& o) noexcept { *this = std::move(o); }

BlockHashTable& BlockHashTable::operator=(BlockHashTable&& o) noexcept {
  entries_ = std::move(o.entries_);
  mask_ = o.mask_, shift_ = o.shift_, max_entries_ = o.max_entries_;
  size_.store(o.size_.load(std::memory_order_relaxed), std::memory_order_relaxed);
  o.mask_ = 0, o.shift_ = 63, o.max_entries_ = 0;
  o.size_.store(0, std::memory_order_relaxed);
  return *this;
}

size_t BlockHashTable::index_of(int x, int y, int z) const {
  if (entries_ == nullptr) return SIZE_MAX;
  for (size_t i = home(x, y, z);; i = (i + 1) & mask_) {
    const Entry& e = entries_[i];
    if (e.value == 0) return SIZE_MAX;
    if (e.x == x && e.y == y && e.z == z) return i;
  }
}

bool BlockHashTable::insert(int x, int y, int z, std::uint32_t value) {
  if (entries_ == nullptr || size() >= max_entries_ || value == 0) return false;
  size_t i = home(x, y, z);
  while (entries_[i].value != 0) i = (i + 1) & mask_;
  Entry& e = entries_[i];
  e.x = x, e.y = y, e.z = z;
  publish(e, value);  // last: a concurrent find() sees the whole entry or an empty one
  size_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

bool BlockHashTable::set_value(int x, int y, int z, std::uint32_t value) {
  const size_t i = index_of(x, y, z);
  if (i == SIZE_MAX || value == 0) return false;
  publish(entries_[i], value);
  return true;
}

std::uint32_t BlockHashTable::erase(int x, int y, int z) {
  size_t hole = index_of(x, y, z);
  if (hole == SIZE_MAX) return 0;
  const std::uint32_t value = entries_[hole].value;
  // Backward shift: move each later entry of the run into the hole unless its home lies cyclically in
  // (hole, j], where it must stay to remain reachable.
  for (size_t j = (hole + 1) & mask_; entries_[j].value != 0; j = (j + 1) & mask_) {
    const size_t h = home(entries_[j].x, entries_[j].y, entries_[j].z);
    const bool stays = hole < j ? (h > hole && h <= j) : (h > hole || h <= j);
    if (stays) continue;
    entries_[hole] = entries_[j];
    hole = j;
  }
  entries_[hole] = Entry{0, 0, 0, 0};
  size_.fetch_sub(1, std::memory_order_relaxed);
  return value;
}

void BlockHashTable::clear() {
  if (entries_ != nullptr) std::memset(static_cast<void*>(entries_.get()), 0, (mask_ + 1) * sizeof(Entry));
  size_ = 0;
}

}  // namespace hf::fusion
