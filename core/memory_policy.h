// How the process's allocator treats freed memory: keep it for reuse instead of handing it back to the kernel.
//
//   int main() { hf::keep_freed_memory_for_reuse(); ... }   // first, before any thread starts
//
// Why: a frame allocates and frees the same few dozen buffers every frame (pyramids, raycast maps, residual
// images: 0.3 to 5 MiB each, on the main thread and on TBB's workers). glibc's defaults return such memory to the
// kernel (mmap'd chunks above the dynamic threshold are unmapped on free; a heap top above the trim threshold, 128
// KiB to 64 MiB, is trimmed), so the next frame touches fresh zero pages and takes a page fault per 4 KiB: measured
// on fr1/rpy, ~1050 minor faults a frame, ~340 fewer with this policy (212 k -> 143 k over 201 frames), 54.2 ->
// 50.3 ms a frame, and 126.6 -> 96.1 ms a frame on the 810-frame ping-pong session whose re-fusion allocates per
// re-fused frame (bench/results/backend.md, "Sessions 4 and 5"). The price is resident memory: freed buffers
// stay resident up to the trim threshold per arena (fr1/rpy peak RSS 659 -> 700 MB).
//
// The policy: allocations up to 32 MiB come from the heap (the mmap threshold, fixed instead of glibc's sliding
// one) and a heap keeps up to 256 MiB of free memory at its top before trimming. Only for executables: a library
// (the Python module) must not change its host process's allocator. No effect without glibc or under a sanitizer's
// allocator (returns false then).
#pragma once

#include <cstddef>

namespace hf {

constexpr std::size_t kMmapThresholdBytes = std::size_t(32) << 20;
constexpr std::size_t kTrimThresholdBytes = std::size_t(256) << 20;

// Applies the policy above; true when the allocator accepted it.
bool keep_freed_memory_for_reuse();

}  // namespace hf
