#include "core/filters.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/parallel.h"
#include "core/kernels/image_kernels.h"

namespace hf {
namespace {

bool positive_finite(float v) { return std::isfinite(v) && v > 0.0f; }

// The bilateral row is worth an AVX2 clone picked at load time (the build targets baseline x86-64; the default
// clone runs the same vector code as SSE pairs).
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define HF_VECTOR_ROW __attribute__((target_clones("avx2", "default")))
#else
#define HF_VECTOR_ROW
#endif

// The helpers below are internal and always inlined, so GCC's note that 32-byte vector arguments change the ABI
// without AVX does not apply.
#if defined(__clang__)
#pragma clang diagnostic ignored "-Wpsabi"
#elif defined(__GNUC__)
#pragma GCC diagnostic ignored "-Wpsabi"
#endif
// Eight floats in one register (GCC/Clang vector extension: AVX in the AVX2 clone, two SSE registers otherwise).
typedef float float8 __attribute__((vector_size(32)));
typedef std::int32_t int8v __attribute__((vector_size(32)));

__attribute__((always_inline)) inline float8 load8(const float* p) {
  float8 v;
  std::memcpy(&v, p, sizeof(v));
  return v;
}

// exp(-t) for t >= 0 without a libm call, eight at a time: 2^z with z = -t log2(e) split into round(z) (the
// exponent bits) and f = z - round(z) in [-0.5, 0.5] (a degree-6 Taylor polynomial of e^(f ln 2), relative error
// < 3e-7, i.e. float rounding). t beyond 87 (weight < 1.7e-38 relative to the centre tap's 1) is clamped there.
__attribute__((always_inline)) inline float8 exp_neg8(float8 t) {
  const float8 limit = float8{} + 87.0f;
  const int8v small = t < limit;  // -1 where t < 87
  t = __builtin_bit_cast(float8, (small & __builtin_bit_cast(int8v, t)) | (~small & __builtin_bit_cast(int8v, limit)));
  const float8 z = t * -1.44269504f;
  const float8 r = (z + 12582912.0f) - 12582912.0f;  // round to nearest (the 1.5 * 2^23 trick); |z| < 2^22
  const float8 f = (z - r) * 0.693147181f;            // 2^(z - r) = e^f, |f| <= 0.347
  const float8 p =
      1.0f + f * (1.0f + f * (0.5f + f * (1.0f / 6.0f + f * (1.0f / 24.0f + f * (1.0f / 120.0f + f * (1.0f / 720.0f))))));
  const int8v bits = (__builtin_convertvector(r, int8v) + 127) << 23;  // 2^r, r in [-126, 0]
  return p * __builtin_bit_cast(float8, bits);
}

// One output row of the bilateral filter, eight pixels at a time with the window's sums in registers. `padded`
// is the depth with invalid samples as 0, a border of `radius` zero pixels on every side and at least 7 more
// zero columns on the right, so taps outside the image carry no weight (the window is clipped) without a branch.
// spatial_exponent[k] = (dx^2 + dy^2) / (2 sigma_s^2) of the window's k-th offset, row-major.
HF_VECTOR_ROW void bilateral_row(const float* padded, int padded_width, int width, int radius,
                                 const float* spatial_exponent, float inv_two_sigma_r2, int y, float* out) {
  const float* centre = padded + size_t(y + radius) * padded_width + radius;
  const int side = 2 * radius + 1;
  for (int x = 0; x < width; x += 8) {
    const float8 c = load8(centre + x);
    float8 sum = float8{}, wsum = float8{};
    for (int j = 0; j < side; ++j) {
      const float* row = centre + std::ptrdiff_t(j - radius) * padded_width + x - radius;
      const float* s = spatial_exponent + j * side;
      for (int i = 0; i < side; ++i) {
        const float8 d = load8(row + i);
        const float8 dd = d - c;
        const float8 w = exp_neg8(s[i] + dd * dd * inv_two_sigma_r2);
        const float8 wv = __builtin_bit_cast(float8, (d > 0.0f) & __builtin_bit_cast(int8v, w));  // holes: 0
        sum += wv * d;
        wsum += wv;
      }
    }
    // An invalid centre stays invalid; a valid one has wsum >= 1 (its own tap, weight exp(0)).
    const int n = std::min(8, width - x);
    for (int k = 0; k < n; ++k) out[x + k] = c[k] > 0.0f ? sum[k] / wsum[k] : 0.0f;
  }
}

}  // namespace

int bilateral_radius_px(const BilateralParams& p) {
  return p.radius_px > 0 ? p.radius_px : int(std::ceil(2.0f * p.sigma_s_px));
}

DepthImage bilateral_filter_depth(const DepthImage& depth, const BilateralParams& p) {
  if (!positive_finite(p.sigma_s_px) || !positive_finite(p.sigma_r_m) || p.radius_px < 0 || p.sigma_s_px > 1e4f ||
      p.radius_px > 1000) {
    throw Error("bilateral_filter_depth: expected finite sigma_s_px in (0, 1e4], sigma_r_m > 0 and radius_px in "
                "[0, 1000], got sigma_s_px=" + std::to_string(p.sigma_s_px) + " sigma_r_m=" +
                std::to_string(p.sigma_r_m) + " radius_px=" + std::to_string(p.radius_px));
  }
  const int radius = bilateral_radius_px(p);
  const float inv_two_sigma_s2 = 1.0f / (2.0f * p.sigma_s_px * p.sigma_s_px);
  const float inv_two_sigma_r2 = 1.0f / (2.0f * p.sigma_r_m * p.sigma_r_m);
  const int w = depth.width(), h = depth.height();
  DepthImage out(w, h);
  if (depth.empty()) return out;
  // Precomputed once: the window's spatial exponents and the zero-padded, sanitised input (invalid = 0).
  std::vector<float> spatial;
  spatial.reserve(size_t(2 * radius + 1) * size_t(2 * radius + 1));
  for (int dy = -radius; dy <= radius; ++dy)
    for (int dx = -radius; dx <= radius; ++dx) spatial.push_back(float(dx * dx + dy * dy) * inv_two_sigma_s2);
  const int pw = w + 2 * radius + 8, ph = h + 2 * radius;
  std::vector<float> padded(size_t(pw) * size_t(ph), 0.0f);
  const float* src = depth.data();
  parallel_for_rows(h, [&](int y) {
    float* row = padded.data() + size_t(y + radius) * pw + radius;
    for (int x = 0; x < w; ++x) {
      const float d = src[size_t(y) * w + x];
      row[x] = hf_depth_is_valid(d) ? d : 0.0f;
    }
  });
  float* dst = out.data();
  parallel_for_rows(h, [&](int y) {
    bilateral_row(padded.data(), pw, w, radius, spatial.data(), inv_two_sigma_r2, y, dst + size_t(y) * w);
  });
  return out;
}

ImageGradients image_gradients(const Image<float>& image) {
  ImageGradients g{Image<float>(image.width(), image.height()), Image<float>(image.width(), image.height())};
  const int w = image.width(), h = image.height();
  const float* src = image.data();
  float* gx = g.dx.data();
  float* gy = g.dy.data();
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      const size_t i = size_t(y) * w + x;
      hf_gradient_pixel(src, w, h, x, y, &gx[i], &gy[i]);
    }
  });
  return g;
}

std::optional<float> sample_bilinear(const Image<float>& image, float x, float y) {
  float v = 0.0f;
  if (image.empty() || !hf_sample_bilinear(image.data(), image.width(), image.height(), x, y, 0, &v)) {
    return std::nullopt;
  }
  return v;
}

std::optional<float> sample_depth_bilinear(const DepthImage& depth, float x, float y) {
  float v = 0.0f;
  if (depth.empty() || !hf_sample_bilinear(depth.data(), depth.width(), depth.height(), x, y, 1, &v)) {
    return std::nullopt;
  }
  return v;
}

}  // namespace hf
