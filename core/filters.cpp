#include "core/filters.h"

#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel.h"
#include "core/kernels/image_kernels.h"

namespace hf {
namespace {

bool positive_finite(float v) { return std::isfinite(v) && v > 0.0f; }

}  // namespace

DepthImage bilateral_filter_depth(const DepthImage& depth, const BilateralParams& p) {
  if (!positive_finite(p.sigma_s_px) || !positive_finite(p.sigma_r_m) || p.radius_px < 0 || p.sigma_s_px > 1e4f) {
    throw Error("bilateral_filter_depth: expected finite sigma_s_px in (0, 1e4], sigma_r_m > 0 and radius_px >= 0, "
                "got sigma_s_px=" + std::to_string(p.sigma_s_px) + " sigma_r_m=" + std::to_string(p.sigma_r_m) +
                " radius_px=" + std::to_string(p.radius_px));
  }
  const int radius = p.radius_px > 0 ? p.radius_px : int(std::ceil(2.0f * p.sigma_s_px));
  const float inv_two_sigma_s2 = 1.0f / (2.0f * p.sigma_s_px * p.sigma_s_px);
  const float inv_two_sigma_r2 = 1.0f / (2.0f * p.sigma_r_m * p.sigma_r_m);
  DepthImage out(depth.width(), depth.height());
  const int w = depth.width(), h = depth.height();
  const float* src = depth.data();
  float* dst = out.data();
  parallel_for_rows(h, [&](int y) {
    for (int x = 0; x < w; ++x) {
      dst[size_t(y) * w + x] = hf_bilateral_depth_pixel(src, w, h, x, y, radius, inv_two_sigma_s2, inv_two_sigma_r2);
    }
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
