// Whether a test runs in the sanitizer build (the asan preset: clang's AddressSanitizer + UndefinedBehaviorSanitizer;
// GCC's -fsanitize=address too), so a few end-to-end accuracy tests can leave that suite. Each that does names the
// shorter tests that run its code paths under the sanitizers; its subject is an accuracy bound, which the Release
// suite checks, and under ASan + UBSan it costs 40-45 s of CI's 30-minute budget (bench/results/ci.md).
#pragma once

namespace hf::test {

#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace hf::test

// Skips the calling test in the sanitizer build; `covered_by` names the tests that run its code there.
#define HF_RELEASE_ONLY_ACCURACY(covered_by)                                                                   \
  do {                                                                                                          \
    if (::hf::test::kSanitized)                                                                                 \
      GTEST_SKIP() << "an accuracy bound checked in the Release suite; under the sanitizers " << (covered_by)   \
                   << " run its code";                                                                          \
  } while (false)
