#include "core/pyramid.h"


#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
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

template <class PixelFn>
Image<float> halve(const Image<float>& src, PixelFn pixel) {
  Image<float> dst(src.width() / 2, src.height() / 2);
  const float* s = src.data();
  float* d = dst.data();
  const int w = dst.width();
  parallel_for_rows(dst.height(), [&](int y) {
    for (int x = 0; x < w; ++x) d[size_t(y) * w + x] = pixel(s, x, y);
  });
  return dst;
}

}  // namespace

Image<float> pyr_down_gaussian(const Image<float>& src) {
  check_halvable(src, "pyr_down_gaussian");
  const int sw = src.width(), sh = src.height();
  return halve(src, [sw, sh](const float* s, int x, int y) { return hf_pyrdown_gaussian_pixel(s, sw, sh, x, y); });
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
  return halve(src, [sw, sh, max_diff_m](const float* s, int x, int y) {
    return hf_pyrdown_depth_pixel(s, sw, sh, x, y, max_diff_m);
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
