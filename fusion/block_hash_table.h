// The hash table under VoxelBlockGrid and BlockLookup: integer block coordinates -> a nonzero 32-bit value, open
// addressing with linear probing, lookups without a lock.
//
// Layout (the same on the OpenCL device, fusion/opencl/): a power-of-two array of 16-byte entries {x, y, z, value},
// value 0 meaning empty, at least twice as many entries as the table may ever hold (load <= 0.5 keeps the probe
// runs short). The home entry of (x, y, z) is the top log2(size) bits of a Fibonacci mix of the three coordinates:
// Niessner's xor hash spreads neighbouring blocks poorly over the low bits a power-of-two table uses, which made
// long probe runs for the misses a raycast mostly asks about (measured when BlockLookup was written).
//
// Concurrency: find() may run concurrently with itself and with insert() / set_value() of any key (an entry is
// published by storing its value last, with release order; find() reads the value first, with acquire order, and
// never looks past an empty entry). Writers (insert, set_value) must be serialised by the caller; erase() and
// clear() need exclusive access (they move entries). The entries are zero pages from calloc, so a large table
// costs address space, not memory, until it fills.
#pragma once

#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>

namespace hf::fusion {

class BlockHashTable {
 public:
  BlockHashTable() = default;
  // A table for at most max_entries keys (entries: bit_ceil(max(16, 2 max_entries))). Throws std::bad_alloc.
  explicit BlockHashTable(size_t max_entries);
  BlockHashTable(BlockHashTable&& o) noexcept;
  BlockHashTable& operator=(BlockHashTable&& o) noexcept;

  // The value stored for (x, y, z), 0 when absent. Lock-free (see above).
  std::uint32_t find(int x, int y, int z) const {
    if (entries_ == nullptr) return 0;
    for (size_t i = home(x, y, z);; i = (i + 1) & mask_) {
      const Entry& e = entries_[i];
      const std::uint32_t v = load(e);
      if (v == 0) return 0;
      if (e.x == x && e.y == y && e.z == z) return v;
    }
  }

  // Writers, serialised by the caller. insert: (x, y, z) must be absent and value nonzero; false when the table
  // already holds max_entries keys. set_value: a present key's new nonzero value (false when absent).
  bool insert(int x, int y, int z, std::uint32_t value);
  bool set_value(int x, int y, int z, std::uint32_t value);
  // Exclusive. Removes (x, y, z) by backward shift (no tombstones, so probe runs stay as short as the load
  // allows); returns its value, 0 when absent.
  std::uint32_t erase(int x, int y, int z);
  void clear();  // exclusive

  size_t size() const { return size_.load(std::memory_order_relaxed); }
  size_t max_entries() const { return max_entries_; }
  size_t bytes() const { return (mask_ + 1) * sizeof(Entry) * (entries_ != nullptr); }

  // f(x, y, z, value) for every key, in table order. Not concurrently with writers.
  template <class F>
  void for_each(F&& f) const {
    if (entries_ == nullptr) return;
    for (size_t i = 0; i <= mask_; ++i)
      if (entries_[i].value != 0) f(entries_[i].x, entries_[i].y, entries_[i].z, entries_[i].value);
  }

 private:
  struct Entry {
    std::int32_t x, y, z;
    std::uint32_t value;  // 0: empty
  };
  static_assert(sizeof(Entry) == 16);
  struct Free {
    void operator()(Entry* p) const { std::free(p); }
  };
  static std::uint32_t load(const Entry& e) {
    return std::atomic_ref<std::uint32_t>(const_cast<std::uint32_t&>(e.value)).load(std::memory_order_acquire);
  }
  static void publish(Entry& e, std::uint32_t value) {
    std::atomic_ref<std::uint32_t>(e.value).store(value, std::memory_order_release);
  }
  size_t home(int x, int y, int z) const {
    const std::uint64_t k = (std::uint64_t(std::uint32_t(x)) * 0x9E3779B97F4A7C15ull) ^
                            (std::uint64_t(std::uint32_t(y)) * 0xC2B2AE3D27D4EB4Full) ^
                            (std::uint64_t(std::uint32_t(z)) * 0x165667B19E3779F9ull);
    return size_t((k * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  // Index of (x, y, z)'s entry, or SIZE_MAX when absent.
  size_t index_of(int x, int y, int z) const;

  std::unique_ptr<Entry[], Free> entries_;
  size_t mask_ = 0;
  int shift_ = 63;  // 64 - log2(entries)
  size_t max_entries_ = 0;
  std::atomic<size_t> size_{0};
};

}  // namespace hf::fusion
