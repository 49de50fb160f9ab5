// The hash table under VoxelBlockGrid and BlockLookup: integer block coordinates -> a nonzero 32-bit value, open
// addressing with linear probing, lookups without a lock.
//
// Layout (the same on the OpenCL device, fusion/opencl/): a power-of-two array of 16-byte entries {x, y, z, value},
// value 0 meaning empty, at least twice as many entries as the table holds keys (load <= 0.5 keeps the probe runs
// short). The home entry of (x, y, z) is the top log2(size) bits of a Fibonacci mix of the three coordinates:
// Niessner's xor hash spreads neighbouring blocks poorly over the low bits a power-of-two table uses, which made
// long probe runs for the misses a raycast mostly asks about (measured when BlockLookup was written).
//
// Growth: the array starts with room for initial_keys keys and doubles when an insert would pass load 0.5, up to
// room for max_entries keys; the table is sized to the map, not to the capacity (a map of 10 k blocks in a pool of
// 131 k used to pay for a 4 MiB table whose probe runs spread over pages nobody needed; bytes_per_voxel counts
// what the table holds, so that is what it reports). A grown array is rehashed by the writer that outgrew it and
// published with one atomic pointer store; the old array is RETIRED, not freed, since a lock-free find() may still
// be probing it; reclaim() frees the retired arrays at a point where the caller knows no find() runs (between
// frames, for the map). Retired arrays hold at most as many bytes as the live one (their sizes halve).
//
// Concurrency: find() may run concurrently with itself and with insert() / set_value() of any key (an entry is
// published by storing its value last, with release order; find() reads the array pointer and then the value,
// with acquire order, and never looks past an empty entry; a find() that started on a retired array sees the
// table as it was before the growth, as if it had run just before the insert that grew it). Writers (insert,
// set_value) must be serialised by the caller; erase(), clear(), reserve() and reclaim() need exclusive access.
#pragma once

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <memory>
#include <vector>

namespace hf::fusion {

class BlockHashTable {
 public:
  // Room for initial_keys keys now (at most max_entries), growing up to max_entries keys. Throws std::bad_alloc.
  static constexpr size_t kDefaultInitialKeys = 2048;
  explicit BlockHashTable(size_t max_entries = 0, size_t initial_keys = kDefaultInitialKeys);
  ~BlockHashTable();
  BlockHashTable(BlockHashTable&& o) noexcept;
  BlockHashTable& operator=(BlockHashTable&& o) noexcept;

  // The value stored for (x, y, z), 0 when absent. Lock-free (see above).
  std::uint32_t find(int x, int y, int z) const {
    const Array* a = current_.load(std::memory_order_acquire);
    for (size_t i = a->home(x, y, z);; i = (i + 1) & a->mask) {
      const Entry& e = a->entries[i];
      const std::uint32_t v = load(e);
      if (v == 0) return 0;
      if (e.x == x && e.y == y && e.z == z) return v;
    }
  }

  // Writers, serialised by the caller. insert: (x, y, z) must be absent and value nonzero; grows the array when
  // needed; false when the table already holds max_entries keys (throws std::bad_alloc when growing fails).
  // set_value: a present key's new nonzero value (false when absent).
  bool insert(int x, int y, int z, std::uint32_t value);
  bool set_value(int x, int y, int z, std::uint32_t value);
  // Exclusive. Removes (x, y, z) by backward shift (no tombstones, so probe runs stay as short as the load
  // allows); returns its value, 0 when absent. The array does not shrink.
  std::uint32_t erase(int x, int y, int z);
  // Exclusive. Empties the table and returns it to its initial room (frees the grown arrays).
  void clear();
  // Exclusive. Grows the array now so that `keys` keys fit without growing (capped at max_entries).
  void reserve(size_t keys);
  // Exclusive: no find() may be probing a retired array. Frees them; returns the bytes freed.
  size_t reclaim();

  size_t size() const { return size_.load(std::memory_order_relaxed); }
  size_t max_entries() const { return max_entries_; }
  // Keys the live array holds before it grows (load 0.5), at most max_entries.
  size_t room() const;
  // Bytes of the live array (what lookups touch) and of the retired ones awaiting reclaim().
  size_t bytes() const { return (live_->mask + 1) * sizeof(Entry); }
  size_t retired_bytes() const;

  // f(x, y, z, value) for every key, in table order. Not concurrently with writers.
  template <class F>
  void for_each(F&& f) const {
    const Array& a = *live_;
    for (size_t i = 0; i <= a.mask; ++i)
      if (a.entries[i].value != 0) f(a.entries[i].x, a.entries[i].y, a.entries[i].z, a.entries[i].value);
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
  // One power-of-two array of entries with its mask and hash shift: what find() reads through one pointer.
  struct Array {
    explicit Array(size_t entries);  // zeroed (calloc); throws std::bad_alloc
    std::unique_ptr<Entry[], Free> entries;
    size_t mask = 0;
    int shift = 63;  // 64 - log2(entries)
    size_t home(int x, int y, int z) const {
      const std::uint64_t k = (std::uint64_t(std::uint32_t(x)) * 0x9E3779B97F4A7C15ull) ^
                              (std::uint64_t(std::uint32_t(y)) * 0xC2B2AE3D27D4EB4Full) ^
                              (std::uint64_t(std::uint32_t(z)) * 0x165667B19E3779F9ull);
      return size_t((k * 0x9E3779B97F4A7C15ull) >> shift);
    }
  };
  static size_t entries_for(size_t keys) { return std::bit_ceil(std::max<size_t>(16, 2 * keys)); }
  static std::uint32_t load(const Entry& e) {
    return std::atomic_ref<std::uint32_t>(const_cast<std::uint32_t&>(e.value)).load(std::memory_order_acquire);
  }
  static void publish(Entry& e, std::uint32_t value) {
    std::atomic_ref<std::uint32_t>(e.value).store(value, std::memory_order_release);
  }
  // Index of (x, y, z)'s entry in the live array, or SIZE_MAX when absent.
  size_t index_of(int x, int y, int z) const;
  // Rehashes every key into a new array of `entries` entries and publishes it; the old one is retired.
  void grow_to(size_t entries);

  size_t max_entries_ = 0;
  size_t initial_keys_ = 0;
  std::unique_ptr<Array> live_;                 // the array writers use
  std::atomic<const Array*> current_{nullptr};  // the same, for lock-free readers
  std::vector<std::unique_ptr<Array>> retired_;
  std::atomic<size_t> size_{0};
};

}  // namespace hf::fusion
