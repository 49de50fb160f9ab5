// core/memory_policy.h: after keep_freed_memory_for_reuse(), memory a thread frees is reused without new page
// faults. 64 MiB in 1 MiB buffers is allocated, touched and freed once; doing it again must fault (almost) no page:
// under glibc's defaults each 1 MiB buffer is mmap'd and unmapped on free (above the initial 128 KiB threshold) or
// trimmed off the heap top, so the second round faults all 16384 of its 4 KiB pages again.
#include <sys/resource.h>

#include <cstdlib>
#include <cstring>
#include <vector>

#include <gtest/gtest.h>

#include "core/memory_policy.h"

namespace {

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_THREAD, &usage);
  return usage.ru_minflt;
}

// Allocates, touches every page of, and frees `count` buffers of `bytes` each.
void churn(size_t count, size_t bytes) {
  std::vector<char*> buffers;
  for (size_t i = 0; i < count; ++i) {
    char* p = static_cast<char*>(std::malloc(bytes));
    ASSERT_NE(p, nullptr);
    std::memset(p, int(i), bytes);
    buffers.push_back(p);
  }
  for (char* p : buffers) std::free(p);
}

TEST(MemoryPolicy, FreedBuffersAreReusedWithoutPageFaults) {
  if (!hf::keep_freed_memory_for_reuse())
    GTEST_SKIP() << "the allocator refused the policy (not glibc, or a sanitizer's allocator): nothing to test";
  constexpr size_t kBuffers = 64, kBytes = size_t(1) << 20;
  churn(kBuffers, kBytes);
  const long before = minor_faults();
  churn(kBuffers, kBytes);
  const long faults = minor_faults() - before;
  // 16384 pages were touched; allow 2 % for the vector's own pages and the allocator's bookkeeping.
  EXPECT_LT(faults, long(kBuffers * kBytes / 4096 / 50)) << "the second round re-faulted its pages";
}

}  // namespace
