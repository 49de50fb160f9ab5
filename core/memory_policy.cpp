#include "core/memory_policy.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace hf {

bool keep_freed_memory_for_reuse() {
#if defined(__GLIBC__)
  // Setting either value turns glibc's dynamic adjustment of both off, so both are set. A sanitizer's allocator
  // intercepts mallopt and answers 0.
  const bool mmap_ok = mallopt(M_MMAP_THRESHOLD, int(kMmapThresholdBytes)) == 1;
  const bool trim_ok = mallopt(M_TRIM_THRESHOLD, int(kTrimThresholdBytes)) == 1;
  return mmap_ok && trim_ok;
#else
  return false;
#endif
}

}  // namespace hf
