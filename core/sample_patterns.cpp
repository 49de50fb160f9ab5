#include "core/sample_patterns.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"

namespace hf {

double halton(std::uint64_t index, int base) {
  double f = 1.0, r = 0.0;
  while (index > 0) {
    f /= base;
    r += f * double(index % std::uint64_t(base));
    index /= std::uint64_t(base);
  }
  return r;
}

namespace {

void check_size(int width, int height) {
  if (width < 1 || height < 1)
    throw Error("sample pattern: size " + std::to_string(width) + "x" + std::to_string(height) + " must be >= 1x1");
}

// Pixel of Halton point k (the index is offset by 1: H(0) = 0 for every base).
size_t halton_pixel(std::uint64_t k, int width, int height) {
  const int x = std::min(width - 1, int(halton(k + 1, 2) * width));
  const int y = std::min(height - 1, int(halton(k + 1, 3) * height));
  return size_t(y) * width + x;
}

}  // namespace

std::vector<std::uint8_t> halton_mask(int width, int height, double coverage, std::uint64_t offset) {
  check_size(width, height);
  if (!(coverage >= 0.0 && coverage <= 1.0))
    throw Error("sample pattern: coverage must be in [0, 1], got " + std::to_string(coverage));
  const size_t n = size_t(width) * height;
  const size_t want = size_t(std::llround(coverage * double(n)));
  std::vector<std::uint8_t> mask(n, 0);
  size_t set = 0;
  // Late in a dense pattern most draws hit set pixels; past 64 draws per pixel the rest are filled in scan order
  // (only for coverage near 1, where every pattern is nearly full anyway).
  for (std::uint64_t k = offset; set < want && k < offset + 64 * std::uint64_t(n); ++k) {
    const size_t p = halton_pixel(k, width, height);
    if (!mask[p]) mask[p] = 1, ++set;
  }
  for (size_t p = 0; p < n && set < want; ++p)
    if (!mask[p]) mask[p] = 1, ++set;
  return mask;
}

std::vector<std::uint8_t> halton_mask(const Image<float>& density, std::uint64_t offset) {
  check_size(density.width(), density.height());
  const size_t n = density.size();
  std::vector<std::uint8_t> mask(n, 0);
  for (size_t p = 0; p < n; ++p)
    if (density.pixels()[p] >= 1.0f) mask[p] = 1;
  for (std::uint64_t k = offset; k < offset + n; ++k) {
    const size_t p = halton_pixel(k, density.width(), density.height());
    if (halton(k + 1, 5) < double(density.pixels()[p])) mask[p] = 1;
  }
  return mask;
}

Image<float> focus_density(int width, int height, float cx, float cy, float radius_px, float floor) {
  check_size(width, height);
  Image<float> d(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      const float r = std::hypot(x - cx, y - cy);
      const float q = r <= radius_px ? 1.0f : (radius_px / r) * (radius_px / r);
      d(x, y) = std::clamp(q, floor, 1.0f);
    }
  return d;
}

}  // namespace hf
