#include "core/mesh_interpolation.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace hf {

MeshInterpolationResult mesh_interpolate(int width, int height, int channels, float* values, std::uint8_t* mask) {
  MeshInterpolationResult result;
  long samples = 0;
  result.fill = push_pull_prepare(width, height, channels, values, mask, &samples);
  if (!push_pull_filled(result.fill.status)) return result;

  // Subdiv2D's bounding rectangle must contain every point strictly; its virtual outer vertices lie far outside.
  cv::Subdiv2D subdiv(cv::Rect(-1, -1, width + 2, height + 2));
  std::vector<cv::Point2f> points;
  points.reserve(size_t(samples));
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x)
      if (mask[size_t(y) * width + x]) points.emplace_back(float(x), float(y));
  subdiv.insert(points);
  std::vector<cv::Vec6f> triangles;
  subdiv.getTriangleList(triangles);

  // Which pixels were samples: interpolated pixels must read only those, never each other.
  const std::vector<std::uint8_t> is_sample(mask, mask + size_t(width) * height);
  auto corner = [&](float u, float v, int* index) {
    const int x = int(std::lround(u)), y = int(std::lround(v));
    if (x < 0 || y < 0 || x >= width || y >= height || float(x) != u || float(y) != v) return false;
    *index = y * width + x;
    return is_sample[size_t(*index)] != 0;
  };
  for (const cv::Vec6f& t : triangles) {
    int ia = 0, ib = 0, ic = 0;
    // Triangles touching Subdiv2D's virtual outer vertices are outside the samples' hull.
    if (!corner(t[0], t[1], &ia) || !corner(t[2], t[3], &ib) || !corner(t[4], t[5], &ic)) continue;
    ++result.triangles;
    const double ax = t[0], ay = t[1], bx = t[2], by = t[3], cx = t[4], cy = t[5];
    const double area = (bx - ax) * (cy - ay) - (by - ay) * (cx - ax);
    if (area == 0.0) continue;
    const int x0 = int(std::min({ax, bx, cx})), x1 = int(std::max({ax, bx, cx}));
    const int y0 = int(std::min({ay, by, cy})), y1 = int(std::max({ay, by, cy}));
    for (int y = y0; y <= y1; ++y)
      for (int x = x0; x <= x1; ++x) {
        const size_t p = size_t(y) * width + x;
        if (mask[p]) continue;
        const double l0 = ((bx - x) * (cy - y) - (by - y) * (cx - x)) / area;
        const double l1 = ((cx - x) * (ay - y) - (cy - y) * (ax - x)) / area;
        const double l2 = 1.0 - l0 - l1;
        if (l0 < -1e-9 || l1 < -1e-9 || l2 < -1e-9) continue;
        for (int c = 0; c < channels; ++c)
          values[p * channels + c] = float(l0 * values[size_t(ia) * channels + c] +
                                           l1 * values[size_t(ib) * channels + c] +
                                           l2 * values[size_t(ic) * channels + c]);
        mask[p] = 1;
      }
  }
  push_pull_finish(mask, long(width) * height, samples, &result.fill);
  return result;
}

}  // namespace hf
