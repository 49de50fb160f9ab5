// Both levels have an AVX2 spelling of their per-pixel kernel for eight interior output pixels at a time (same
// operations in the same order, no FMA: this file is compiled with -ffp-contract=off, so the same bits;
// tests/core/test_pyramid.cpp holds each image to its kernel). Why: the depth kernel's branches (validity,
// 3 sigma_r test, the insertion sort) cost ~170 ns per output pixel, 9.8 % of the SLAM pipeline's time on
// fr1/rpy; eight pixels share one pass over the 6 x 6 taps as lane masks.
#include "core/pyramid.h"

#include <cmath>
#include <limits>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
#include "core/simd_avx2.h"
#include "core/kernels/image_kernels.h"

namespace hf {
namespace {

void check_halvable(const Image<float>& src, const char* what) {
  if (src.width() < 2 || src.height() < 2) {
    throw Error(std::string(what) + ": a " + std::to_string(src.width()) + "x" + std::to_string(src.height()) +
                " image cannot be halved (need at least 2x2)");
  }
}

void check_levels(int levels, const char* what) {
  if (levels < 1) throw Error(std::string(what) + ": expected levels >= 1, got " + std::to_string(levels));
}

#ifdef HF_HAVE_AVX2_PATH

using namespace hf::avx2;

// Elements p[0], p[2], ..., p[14].
HF_AVX2_INLINE __m256 even16(const float* p) {
  const __m256 a = _mm256_loadu_ps(p), b = _mm256_loadu_ps(p + 8);
  const __m256 e = _mm256_shuffle_ps(a, b, _MM_SHUFFLE(2, 0, 2, 0));  // (0 2 8 10 | 4 6 12 14)
  return _mm256_castpd_ps(_mm256_permute4x64_pd(_mm256_castps_pd(e), _MM_SHUFFLE(3, 1, 2, 0)));
}

// hf_pyrdown_gaussian_pixel for output pixels x0 .. x0 + 7 of row y (the same conditions as pyr_down_depth_8).
HF_AVX2 void pyr_down_gaussian_8(const float* src, int sw, int x0, int y, float* out) {
  __m256 sum = _mm256_setzero_ps();
  for (int j = 0; j < 6; ++j) {
    const float* row = src + size_t(2 * y - 2 + j) * sw + 2 * x0 - 2;
    __m256 r = _mm256_setzero_ps();
    for (int i = 0; i < 6; ++i) r = add(r, mul(splat(hf_pyramid_tap_weight(i)), even16(row + i)));
    sum = add(sum, mul(splat(hf_pyramid_tap_weight(j)), r));
  }
  _mm256_storeu_ps(out, sum);
}

HF_AVX2_INLINE void sort2(__m256& a, __m256& b) {
  const __m256 lo = _mm256_min_ps(a, b);
  b = _mm256_max_ps(a, b);
  a = lo;
}

// hf_pyrdown_depth_pixel for output pixels x0 .. x0 + 7 of row y, all of whose taps lie inside the image, and
// src[(2 y - 2 + j) * sw + 2 x0 + 18] too (the last 16-float load reads one beyond the last tap).
HF_AVX2 void pyr_down_depth_8(const float* src, int sw, int x0, int y, float max_diff_m, float* out) {
  const __m256 zero = _mm256_setzero_ps(), inf = splat(std::numeric_limits<float>::infinity());
  const __m256 max_diff = splat(max_diff_m), sign = splat(-0.0f);
  auto valid = [&](__m256 d) HF_AVX2_LAMBDA { return and_(cmp_gt(d, zero), cmp_lt(d, inf)); };
  // The 2 x 2 block, invalid samples as +inf: sorted, the valid ones come first in order, which is what the
  // kernel's insertion sort builds.
  __m256 s[4];
  __m256 n = zero;
  for (int k = 0; k < 4; ++k) {
    const __m256 d = even16(src + size_t(2 * y + (k >> 1)) * sw + 2 * x0 + (k & 1));
    const __m256 ok = valid(d);
    s[k] = select(ok, d, inf);
    n = add(n, and_(ok, splat(1.0f)));
  }
  sort2(s[0], s[1]);
  sort2(s[2], s[3]);
  sort2(s[0], s[2]);
  sort2(s[1], s[3]);
  sort2(s[1], s[2]);
  const __m256 median = select(cmp_le(n, splat(2.0f)), s[0], s[1]);
  __m256 ref_sum = zero, ref_n = zero;
  for (int k = 0; k < 4; ++k) {
    const __m256 in = cmp_le(_mm256_andnot_ps(sign, sub(s[k], median)), max_diff);  // false for the +inf ones
    ref_sum = add(ref_sum, and_(in, s[k]));
    ref_n = add(ref_n, and_(in, splat(1.0f)));
  }
  const __m256 ref = div(ref_sum, ref_n);  // NaN where the block has no valid sample: every test below fails
  __m256 sum = zero, wsum = zero;
  for (int j = 0; j < 6; ++j) {
    const float* row = src + size_t(2 * y - 2 + j) * sw + 2 * x0 - 2;
    for (int i = 0; i < 6; ++i) {
      const __m256 d = even16(row + i);
      const __m256 keep = and_(valid(d), cmp_le(_mm256_andnot_ps(sign, sub(d, ref)), max_diff));
      const __m256 w = splat(hf_pyramid_tap_weight(i) * hf_pyramid_tap_weight(j));
      sum = add(sum, and_(mul(w, d), keep));
      wsum = add(wsum, and_(w, keep));
    }
  }
  const __m256 mean = select(cmp_gt(wsum, zero), div(sum, wsum), median);
  _mm256_storeu_ps(out, and_(cmp_gt(n, zero), mean));
}

#endif

// The half-size image of src: pixel(s, x, y) is one output pixel of a 6 x 6-window kernel; where the processor
// has AVX2, pixel8(s, x0, y, out) writes the eight pixels x0 .. x0 + 7 of rows whose windows lie inside the
// image, for x0 >= 1 and 2 x0 + 18 < width (its 16-float loads read one float beyond the last tap).
template <class PixelFn, class Pixel8Fn>
Image<float> halve(const Image<float>& src, PixelFn pixel, [[maybe_unused]] Pixel8Fn pixel8) {
  Image<float> dst(src.width() / 2, src.height() / 2);
  const int sw = src.width(), sh = src.height(), w = dst.width();
  const float* s = src.data();
  [[maybe_unused]] const bool simd = cpu_has_avx2();
  parallel_for_rows(dst.height(), [&](int y) {
    float* out = dst.data() + size_t(y) * w;
    int x = 0;
#ifdef HF_HAVE_AVX2_PATH
    if (simd && 2 * y - 2 >= 0 && 2 * y + 3 < sh) {
      for (; x < 1; ++x) out[x] = pixel(s, x, y);
      for (; 2 * x + 18 < sw; x += 8) pixel8(s, x, y, out + x);
    }
#endif
    for (; x < w; ++x) out[x] = pixel(s, x, y);
  });
  return dst;
}

}  // namespace

Image<float> pyr_down_gaussian(const Image<float>& src) {
  check_halvable(src, "pyr_down_gaussian");
  const int sw = src.width(), sh = src.height();
  return halve(
      src, [sw, sh](const float* s, int x, int y) { return hf_pyrdown_gaussian_pixel(s, sw, sh, x, y); },
      [sw](const float* s, int x0, int y, float* out) {
#ifdef HF_HAVE_AVX2_PATH
        pyr_down_gaussian_8(s, sw, x0, y, out);
#else
        (void)s, (void)x0, (void)y, (void)out, (void)sw;
#endif
      });
}

std::vector<Image<float>> build_gaussian_pyramid(const Image<float>& level0, int levels) {
  check_levels(levels, "build_gaussian_pyramid");
  std::vector<Image<float>> pyramid{level0};
  pyramid.reserve(size_t(levels));
  for (int l = 1; l < levels; ++l) pyramid.push_back(pyr_down_gaussian(pyramid.back()));
  return pyramid;
}

DepthImage pyr_down_depth(const DepthImage& src, float sigma_r_m) {
  check_halvable(src, "pyr_down_depth");
  if (!(std::isfinite(sigma_r_m) && sigma_r_m > 0.0f)) {
    throw Error("pyr_down_depth: expected a finite sigma_r_m > 0, got " + std::to_string(sigma_r_m));
  }
  const int sw = src.width(), sh = src.height();
  const float max_diff_m = 3.0f * sigma_r_m;
  return halve(
      src, [sw, sh, max_diff_m](const float* s, int x, int y) {
        return hf_pyrdown_depth_pixel(s, sw, sh, x, y, max_diff_m);
      },
      [sw, max_diff_m](const float* s, int x0, int y, float* out) {
#ifdef HF_HAVE_AVX2_PATH
        pyr_down_depth_8(s, sw, x0, y, max_diff_m, out);
#else
        (void)s, (void)x0, (void)y, (void)out, (void)sw, (void)max_diff_m;
#endif
      });
}

std::vector<DepthImage> build_depth_pyramid(const DepthImage& level0, int levels, float sigma_r_m) {
  check_levels(levels, "build_depth_pyramid");
  std::vector<DepthImage> pyramid{level0};
  pyramid.reserve(size_t(levels));
  for (int l = 1; l < levels; ++l) pyramid.push_back(pyr_down_depth(pyramid.back(), sigma_r_m));
  return pyramid;
}

}  // namespace hf
