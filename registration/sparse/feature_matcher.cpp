#include "registration/sparse/feature_matcher.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>

#include <opencv2/core.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "core/kernels/image_kernels.h"

namespace hf {
namespace {

cv::Mat to_gray8(const IntensityImage& intensity) {
  cv::Mat gray(intensity.height(), intensity.width(), CV_8UC1);
  for (int y = 0; y < intensity.height(); ++y) {
    auto* row = gray.ptr<std::uint8_t>(y);
    for (int x = 0; x < intensity.width(); ++x) {
      const float v = intensity(x, y);
      row[x] = std::isfinite(v) ? std::uint8_t(std::clamp(v, 0.0f, 1.0f) * 255.0f + 0.5f) : 0;
    }
  }
  return gray;
}

// The keypoint's depth by bilinear interpolation of the four surrounding vertices' z, or nothing where one is
// invalid or they straddle a depth edge.
bool keypoint_depth(const VertexMap& vertices, float u, float v, float edge_sigmas, double* z) {
  const int x0 = int(std::floor(u)), y0 = int(std::floor(v));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= vertices.width() || y0 + 1 >= vertices.height()) return false;
  float zs[4];
  for (int k = 0; k < 4; ++k) {
    const hf_float4& p = vertices(x0 + (k & 1), y0 + (k >> 1));
    if (p.w == 0.0f || !(p.z > 0.0f)) return false;
    zs[k] = p.z;
  }
  const float lo = *std::min_element(zs, zs + 4), hi = *std::max_element(zs, zs + 4);
  if (hi - lo > edge_sigmas * hf_kinect_axial_sigma_m(hi)) return false;
  const double ax = double(u) - x0, ay = double(v) - y0;
  *z = (1 - ay) * ((1 - ax) * zs[0] + ax * zs[1]) + ay * ((1 - ax) * zs[2] + ax * zs[3]);
  return true;
}

}  // namespace

int hamming_distance(const std::array<std::uint64_t, 4>& a, const std::array<std::uint64_t, 4>& b) {
  return std::popcount(a[0] ^ b[0]) + std::popcount(a[1] ^ b[1]) + std::popcount(a[2] ^ b[2]) +
         std::popcount(a[3] ^ b[3]);
}

FeatureFrame extract_features(const FramePyramidLevel& level, const FeatureOptions& options) {
  FeatureFrame frame;
  frame.camera = level.camera;
  if (!level.has_intensity() || level.vertices.width() != level.intensity.width() ||
      level.vertices.height() != level.intensity.height()) {
    return frame;
  }
  cv::Mat gray = to_gray8(level.intensity);
  if (options.equalize_histogram) cv::equalizeHist(gray.clone(), gray);
  cv::Ptr<cv::ORB> orb = cv::ORB::create(options.max_features, options.scale_factor, options.scale_levels,
                                         options.patch_px, 0, 2, cv::ORB::HARRIS_SCORE, options.patch_px,
                                         options.fast_threshold);
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
  orb->detectAndCompute(gray, cv::noArray(), keypoints, descriptors);
  if (keypoints.empty() || descriptors.rows != int(keypoints.size()) || descriptors.cols != 32) return frame;
  frame.features.reserve(keypoints.size());
  for (size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& k = keypoints[i];
    double z = 0.0;
    const cv::Point2f& c = k.pt;
    if (!keypoint_depth(level.vertices, c.x, c.y, options.depth_edge_sigmas, &z)) continue;
    Feature f;
    f.pixel = {c.x, c.y};
    f.point_m = level.camera.backproject(c.x, c.y, z);
    f.octave = k.octave;
    f.scale = std::pow(options.scale_factor, float(k.octave));
    std::memcpy(f.descriptor.data(), descriptors.ptr<std::uint8_t>(int(i)), 32);
    frame.features.push_back(f);
  }
  return frame;
}

namespace {

// The nearest and second-nearest feature of `to` for descriptor d: (index, best, second best distance).
struct Nearest {
  int index = -1;
  int best = std::numeric_limits<int>::max();
  int second = std::numeric_limits<int>::max();
};

Nearest nearest(const std::array<std::uint64_t, 4>& d, const FeatureFrame& to) {
  Nearest n;
  for (size_t j = 0; j < to.features.size(); ++j) {
    const int dist = hamming_distance(d, to.features[j].descriptor);
    if (dist < n.best) {
      n.second = n.best;
      n.best = dist;
      n.index = int(j);
    } else if (dist < n.second) {
      n.second = dist;
    }
  }
  return n;
}

}  // namespace

std::vector<FeatureMatch> match_features(const FeatureFrame& current, const FeatureFrame& reference,
                                         const MatchOptions& options) {
  std::vector<FeatureMatch> matches;
  if (current.empty() || reference.empty()) return matches;
  for (size_t i = 0; i < current.features.size(); ++i) {
    const Nearest n = nearest(current.features[i].descriptor, reference);
    if (n.index < 0 || n.best > options.max_distance_bits) continue;
    // A lone reference feature has no second best: the ratio test cannot reject it.
    if (n.second != std::numeric_limits<int>::max() && !(float(n.best) < options.ratio * float(n.second))) continue;
    if (options.cross_check && nearest(reference.features[size_t(n.index)].descriptor, current).index != int(i)) {
      continue;
    }
    matches.push_back({int(i), n.index, n.best});
  }
  return matches;
}

}  // namespace hf
