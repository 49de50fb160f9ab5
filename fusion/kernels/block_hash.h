// The voxel-block hash as kernels read it: the layout of fusion/block_hash_table.h (BlockHashTable, under
// VoxelBlockGrid) as a flat array, shared by the OpenCL programs (fusion/opencl/*.cl, the sdf reduction kernel)
// and the C++ code that builds or checks that layout (fusion/flat_block_map.h, fusion/opencl/device_voxel_grid.cpp),
// in the common subset of C++ and OpenCL C 1.2 (core/kernels/cl_compat.h).
//
// A table of 2^n 16-byte entries {x, y, z, value}, value = pool slot + 1 (0: empty), at most half full; the home
// entry of block (x, y, z) is the top n bits of a Fibonacci mix of the coordinates (shift = 64 - n); linear
// probing. The pool holds HF_VOXELS_PER_BLOCK hf_voxels per slot (fusion/kernels/voxel.h), x fastest.
#ifndef HF_FUSION_KERNELS_BLOCK_HASH_H
#define HF_FUSION_KERNELS_BLOCK_HASH_H

#include "core/kernels/cl_compat.h"
#include "fusion/kernels/voxel.h"

#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
typedef uint hf_uint32;
typedef ulong hf_uint64;
#else
typedef std::uint32_t hf_uint32;
typedef std::uint64_t hf_uint64;
#endif

typedef struct {
  int x, y, z;
  hf_uint32 value;  // pool slot + 1; 0: empty
} hf_block_entry;

// BlockHashTable::home.
HF_INLINE hf_uint32 hf_block_home(int x, int y, int z, int shift) {
  const hf_uint64 k = ((hf_uint64)(hf_uint32)x * (hf_uint64)0x9E3779B97F4A7C15ul) ^
                      ((hf_uint64)(hf_uint32)y * (hf_uint64)0xC2B2AE3D27D4EB4Ful) ^
                      ((hf_uint64)(hf_uint32)z * (hf_uint64)0x165667B19E3779F9ul);
  return (hf_uint32)((k * (hf_uint64)0x9E3779B97F4A7C15ul) >> shift);
}

// The entry holding (x, y, z), or -1: absent (the probe reached an empty entry) or not within max_probe entries
// of its home (the bound a device insert keeps, so a look-up never walks a damaged table for ever).
HF_INLINE int hf_block_find(const HF_GLOBAL hf_block_entry* table, hf_uint32 mask, int shift, int max_probe, int x,
                            int y, int z) {
  hf_uint32 e = hf_block_home(x, y, z, shift);
  for (int i = 0; i < max_probe; ++i, e = (e + 1u) & mask) {
    const hf_block_entry entry = table[e];
    if (entry.value == 0u) return -1;
    if (entry.x == x && entry.y == y && entry.z == z) return (int)e;
  }
  return -1;
}

// floor(i / 8) for any int (block of a voxel index), spelled without a right shift of a negative value, which
// OpenCL C leaves to the implementation.
HF_INLINE int hf_block_of_voxel(int i) {
  return i >= 0 ? i / HF_BLOCK_SIZE : -((HF_BLOCK_SIZE - 1 - i) / HF_BLOCK_SIZE);
}

#endif
