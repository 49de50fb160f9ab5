#include "core/undistort.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/parallel.h"

namespace hf {
namespace {

void undistort_check_size(int width, int height, const PinholeCamera& c, const char* what) {
  if (width != c.width || height != c.height)
    throw Error(std::string("undistort: ") + what + " is " + std::to_string(width) + "x" + std::to_string(height) +
                ", camera is " + std::to_string(c.width) + "x" + std::to_string(c.height));
}

}  // namespace

Undistorter::Undistorter(const PinholeCamera& camera) : pinhole_(camera.pinhole()) {
  const int w = camera.width, h = camera.height;
  const size_t n = size_t(w) * size_t(h);
  nearest_.assign(n, -1);
  corner_.assign(n, -1);
  wx_.assign(n, 0);
  wy_.assign(n, 0);
  parallel_for_rows(h, [&](int v) {
    for (int u = 0; u < w; ++u) {
      const Eigen::Vector2d xn((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy);
      const Eigen::Vector2d xd = camera.distortion.distort(xn);
      const double su = camera.fx * xd.x() + camera.cx, sv = camera.fy * xd.y() + camera.cy;
      const size_t i = size_t(v) * size_t(w) + size_t(u);
      // Pixel centres are integers: a source position within half a pixel of the border still has a nearest
      // pixel. Colour is always sampled, clamped onto the last full footprint: a ray the stored image did not see
      // repeats the border colour, because a fixed black frame would be a strong edge that does not move with the
      // camera, which photometric rows would lock onto.
      if (su > -0.5 && su < w - 0.5 && sv > -0.5 && sv < h - 0.5)
        nearest_[i] = std::int32_t(int(std::lround(sv)) * w + int(std::lround(su)));
      const double cu = std::min(std::max(su, 0.0), w - 1.0), cv = std::min(std::max(sv, 0.0), h - 1.0);
      const int x0 = w > 1 ? std::min(int(cu), w - 2) : 0, y0 = h > 1 ? std::min(int(cv), h - 2) : 0;
      corner_[i] = std::int32_t(y0 * w + x0);
      wx_[i] = std::uint8_t(std::lround(std::min(std::max(cu - x0, 0.0), 1.0) * 255.0));
      wy_[i] = std::uint8_t(std::lround(std::min(std::max(cv - y0, 0.0), 1.0) * 255.0));
    }
  });
}

DepthImage Undistorter::depth(const DepthImage& in) const {
  undistort_check_size(in.width(), in.height(), pinhole_, "depth");
  DepthImage out(in.width(), in.height(), 0.0f);
  const float* src = in.data();
  float* dst = out.data();
  const int w = in.width();
  parallel_for_rows(in.height(), [&](int v) {
    for (size_t i = size_t(v) * size_t(w), end = i + size_t(w); i < end; ++i)
      if (nearest_[i] >= 0) dst[i] = src[nearest_[i]];
  });
  return out;
}

ColorImage Undistorter::color(const ColorImage& in) const {
  if (in.empty()) return {};
  undistort_check_size(in.width(), in.height(), pinhole_, "colour");
  ColorImage out(in.width(), in.height());
  const Rgb8* src = in.data();
  Rgb8* dst = out.data();
  const int w = in.width();
  // A 1-pixel-wide or -high image has no second neighbour: its footprint repeats the pixel.
  const int right = w > 1 ? 1 : 0, down = in.height() > 1 ? w : 0;
  parallel_for_rows(in.height(), [&](int v) {
    for (size_t i = size_t(v) * size_t(w), end = i + size_t(w); i < end; ++i) {
      const std::int32_t c = corner_[i];
      const unsigned ax = wx_[i], ay = wy_[i], bx = 255u - ax, by = 255u - ay;
      const Rgb8 &p00 = src[c], &p10 = src[c + right], &p01 = src[c + down], &p11 = src[c + down + right];
      auto blend = [&](std::uint8_t Rgb8::*ch) {
        const unsigned top = bx * (p00.*ch) + ax * (p10.*ch), bottom = bx * (p01.*ch) + ax * (p11.*ch);
        return std::uint8_t((by * top + ay * bottom + 255u * 255u / 2u) / (255u * 255u));
      };
      dst[i] = Rgb8{blend(&Rgb8::r), blend(&Rgb8::g), blend(&Rgb8::b)};
    }
  });
  return out;
}

}  // namespace hf
