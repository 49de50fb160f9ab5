// AVX2 lane helpers for the eight-at-a-time paths beside the scalar kernels (registration/cpu_backend_avx2.cpp,
// fusion/integrate_cpu.cpp), chosen at run time:
//
//   if (hf::cpu_has_avx2()) run_avx2(...); else run_scalar(...);
//
// HF_HAVE_AVX2_PATH is defined where the compiler can emit AVX2 code for functions marked HF_AVX2 (x86-64, gcc or
// clang) without building the whole program for AVX2: the rest of the binary keeps the baseline instruction set
// and still runs on processors without it. Files using these helpers are compiled with -ffp-contract=off, so the
// lane maths is the scalar kernels' own (a * b + c stays a multiply and an add; fused multiply-adds are only the
// ones written explicitly).
#pragma once

#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#define HF_HAVE_AVX2_PATH 1
#include <immintrin.h>
#endif

namespace hf {

// Whether this processor runs AVX2 and FMA code (checked once).
inline bool cpu_has_avx2() {
#ifdef HF_HAVE_AVX2_PATH
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;
#endif
}

#ifdef HF_HAVE_AVX2_PATH

#define HF_AVX2 __attribute__((target("avx2,fma")))
#define HF_AVX2_INLINE __attribute__((target("avx2,fma"), always_inline)) inline
#define HF_AVX2_LAMBDA __attribute__((target("avx2,fma"), always_inline))

namespace avx2 {

HF_AVX2_INLINE __m256 splat(float v) { return _mm256_set1_ps(v); }
HF_AVX2_INLINE __m256 mul(__m256 a, __m256 b) { return _mm256_mul_ps(a, b); }
HF_AVX2_INLINE __m256 add(__m256 a, __m256 b) { return _mm256_add_ps(a, b); }
HF_AVX2_INLINE __m256 sub(__m256 a, __m256 b) { return _mm256_sub_ps(a, b); }
HF_AVX2_INLINE __m256 div(__m256 a, __m256 b) { return _mm256_div_ps(a, b); }
HF_AVX2_INLINE __m256 and_(__m256 a, __m256 b) { return _mm256_and_ps(a, b); }
HF_AVX2_INLINE __m256 or_(__m256 a, __m256 b) { return _mm256_or_ps(a, b); }
// Where mask is set b, else a (mask lanes all-ones or all-zeros).
HF_AVX2_INLINE __m256 select(__m256 mask, __m256 b, __m256 a) { return _mm256_blendv_ps(a, b, mask); }
HF_AVX2_INLINE __m256 cmp_gt(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
HF_AVX2_INLINE __m256 cmp_ge(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
HF_AVX2_INLINE __m256 cmp_le(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LE_OQ); }
HF_AVX2_INLINE __m256 cmp_lt(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
// a != b, true for NaN like C's !=.
HF_AVX2_INLINE __m256 cmp_ne(__m256 a, __m256 b) { return _mm256_cmp_ps(a, b, _CMP_NEQ_UQ); }
HF_AVX2_INLINE bool none(__m256 mask) { return _mm256_movemask_ps(mask) == 0; }
HF_AVX2_INLINE int count(__m256 mask) { return __builtin_popcount(unsigned(_mm256_movemask_ps(mask))); }
// 0, 1, ..., 7.
HF_AVX2_INLINE __m256 iota() { return _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f); }

// Gathers of 32-bit values at element offsets idx (invalid lanes must hold a safe offset, e.g. 0).
HF_AVX2_INLINE __m256 gather(const float* base, __m256i idx) { return _mm256_i32gather_ps(base, idx, 4); }
// The same where mask is set; 0 elsewhere (those lanes' offsets are not read).
HF_AVX2_INLINE __m256 gather(const float* base, __m256i idx, __m256 mask) {
  return _mm256_mask_i32gather_ps(_mm256_setzero_ps(), base, idx, mask, 4);
}

}  // namespace avx2

#endif

}  // namespace hf
