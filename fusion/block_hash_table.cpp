#include "fusion/block_hash_table.h"

#include <algorithm>
#include <cstring>
#include <new>
#include <utility>

namespace hf::fusion {

BlockHashTable::Array::Array(size_t n) : entries(static_cast<Entry*>(std::calloc(n, sizeof(Entry)))) {
  if (entries == nullptr) throw std::bad_alloc();
  mask = n - 1;
  shift = 64 - std::countr_zero(n);
}

BlockHashTable::BlockHashTable(size_t max_entries, size_t initial_keys)
    : max_entries_(max_entries),
      initial_keys_(std::min(max_entries, initial_keys)),
      live_(std::make_unique<Array>(entries_for(initial_keys_))) {
  current_.store(live_.get(), std::memory_order_release);
}

BlockHashTable::~BlockHashTable() = default;

BlockHashTable::BlockHashTable(BlockHashTable&& o) noexcept { *this = std::move(o); }

BlockHashTable& BlockHashTable::operator=(BlockHashTable&& o) noexcept {
  max_entries_ = o.max_entries_, initial_keys_ = o.initial_keys_;
  live_ = std::move(o.live_);
  retired_ = std::move(o.retired_);
  current_.store(live_.get(), std::memory_order_release);
  size_.store(o.size_.load(std::memory_order_relaxed), std::memory_order_relaxed);
  // The moved-from table stays usable (empty, room for nothing until it grows): find() must not read null.
  o.max_entries_ = 0, o.initial_keys_ = 0;
  o.live_ = std::make_unique<Array>(entries_for(0));  // 256 bytes; only allocation failure could throw here
  o.current_.store(o.live_.get(), std::memory_order_release);
  o.size_.store(0, std::memory_order_relaxed);
  return *this;
}

size_t BlockHashTable::room() const { return std::min(max_entries_, (live_->mask + 1) / 2); }

size_t BlockHashTable::retired_bytes() const {
  size_t bytes = 0;
  for (const auto& a : retired_) bytes += (a->mask + 1) * sizeof(Entry);
  return bytes;
}

size_t BlockHashTable::index_of(int x, int y, int z) const {
  const Array& a = *live_;
  for (size_t i = a.home(x, y, z);; i = (i + 1) & a.mask) {
    const Entry& e = a.entries[i];
    if (e.value == 0) return SIZE_MAX;
    if (e.x == x && e.y == y && e.z == z) return i;
  }
}

void BlockHashTable::grow_to(size_t entries) {
  auto grown = std::make_unique<Array>(entries);
  const Array& old = *live_;
  for (size_t i = 0; i <= old.mask; ++i) {
    const Entry& e = old.entries[i];
    if (e.value == 0) continue;
    size_t j = grown->home(e.x, e.y, e.z);
    while (grown->entries[j].value != 0) j = (j + 1) & grown->mask;
    grown->entries[j] = e;
  }
  // Every entry is written before the pointer is published (release), so a reader that sees the new array sees
  // it whole; readers still on the old one keep a valid array until reclaim().
  current_.store(grown.get(), std::memory_order_release);
  retired_.push_back(std::move(live_));
  live_ = std::move(grown);
}

void BlockHashTable::reserve(size_t keys) {
  keys = std::min(keys, max_entries_);
  if (keys > room()) grow_to(entries_for(keys));
}

size_t BlockHashTable::reclaim() {
  const size_t bytes = retired_bytes();
  retired_.clear();
  return bytes;
}

bool BlockHashTable::insert(int x, int y, int z, std::uint32_t value) {
  if (size() >= max_entries_ || value == 0) return false;
  if (size() + 1 > room()) grow_to((live_->mask + 1) * 2);  // doubling: O(1) amortised per insert
  Array& a = *live_;
  size_t i = a.home(x, y, z);
  while (a.entries[i].value != 0) i = (i + 1) & a.mask;
  Entry& e = a.entries[i];
  e.x = x, e.y = y, e.z = z;
  publish(e, value);  // last: a concurrent find() sees the whole entry or an empty one
  size_.fetch_add(1, std::memory_order_relaxed);
  return true;
}

bool BlockHashTable::set_value(int x, int y, int z, std::uint32_t value) {
  const size_t i = index_of(x, y, z);
  if (i == SIZE_MAX || value == 0) return false;
  publish(live_->entries[i], value);
  return true;
}

std::uint32_t BlockHashTable::erase(int x, int y, int z) {
  size_t hole = index_of(x, y, z);
  if (hole == SIZE_MAX) return 0;
  Array& a = *live_;
  const std::uint32_t value = a.entries[hole].value;
  // Backward shift: move each later entry of the run into the hole unless its home lies cyclically in
  // (hole, j], where it must stay to remain reachable.
  for (size_t j = (hole + 1) & a.mask; a.entries[j].value != 0; j = (j + 1) & a.mask) {
    const size_t h = a.home(a.entries[j].x, a.entries[j].y, a.entries[j].z);
    const bool stays = hole < j ? (h > hole && h <= j) : (h > hole || h <= j);
    if (stays) continue;
    a.entries[hole] = a.entries[j];
    hole = j;
  }
  a.entries[hole] = Entry{0, 0, 0, 0};
  size_.fetch_sub(1, std::memory_order_relaxed);
  return value;
}

void BlockHashTable::clear() {
  if (live_->mask + 1 == entries_for(initial_keys_)) {
    std::memset(static_cast<void*>(live_->entries.get()), 0, (live_->mask + 1) * sizeof(Entry));
  } else {
    live_ = std::make_unique<Array>(entries_for(initial_keys_));
    current_.store(live_.get(), std::memory_order_release);
  }
  retired_.clear();
  size_ = 0;
}

}  // namespace hf::fusion
