#include "io/image_io.h"

#include <cmath>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"

namespace hf {
namespace {

// cv::imread prints its own warning for a missing file and may throw cv::Exception on corrupt data; checking
// first and catching keeps the failure a single hf::Error naming the file.
cv::Mat read_image(const std::string& path, int flags, const char* what) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw Error(path + ": " + what + " image file not found");
  cv::Mat image;
  try {
    image = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot decode " + what + " image (" + e.msg + ")");
  }
  if (image.empty()) throw Error(path + ": cannot decode " + what + " image (truncated or not an image)");
  return image;
}

}  // namespace

DepthImage depth_from_raw16(const std::uint16_t* raw, int width, int height, const DepthDecoding& decoding) {
  if (!(decoding.scale > 0.0) || !std::isfinite(decoding.scale))
    throw Error("depth scale must be a positive number, got " + std::to_string(decoding.scale));
  DepthImage depth(width, height);
  const double inv_scale = 1.0 / decoding.scale;
  float* out = depth.data();
  const size_t n = depth.size();
  for (size_t i = 0; i < n; ++i) {
    const int r = raw[i];
    out[i] = (r == 0 || r == decoding.invalid_raw) ? 0.0f : float(r * inv_scale);
  }
  return depth;
}

DepthImage load_depth(const std::string& path, const DepthDecoding& decoding) {
  if (!(decoding.scale > 0.0) || !std::isfinite(decoding.scale))
    throw Error(path + ": depth scale must be a positive number, got " + std::to_string(decoding.scale));
  const cv::Mat image = read_image(path, cv::IMREAD_ANYDEPTH | cv::IMREAD_GRAYSCALE, "depth");
  if (image.channels() != 1) throw Error(path + ": expected a single-channel depth image");
  const int w = image.cols, h = image.rows;
  if (image.depth() == CV_16U) {
    if (image.isContinuous()) return depth_from_raw16(image.ptr<std::uint16_t>(0), w, h, decoding);
    const cv::Mat copy = image.clone();
    return depth_from_raw16(copy.ptr<std::uint16_t>(0), w, h, decoding);
  }
  if (image.depth() == CV_32F || image.depth() == CV_64F) {
    DepthImage depth(w, h);
    cv::Mat f;
    image.convertTo(f, CV_32F);
    for (int y = 0; y < h; ++y) {
      const float* row = f.ptr<float>(y);
      for (int x = 0; x < w; ++x) depth(x, y) = (std::isfinite(row[x]) && row[x] > 0.0f) ? row[x] : 0.0f;
    }
    return depth;
  }
  throw Error(path + ": expected a 16-bit or 32-bit float depth image, got " +
              std::to_string(image.elemSize1() * 8) + "-bit samples");
}

ColorImage load_color(const std::string& path) {
  const cv::Mat bgr = read_image(path, cv::IMREAD_COLOR, "colour");
  if (bgr.type() != CV_8UC3) throw Error(path + ": expected an 8-bit colour image");
  ColorImage color(bgr.cols, bgr.rows);
  for (int y = 0; y < bgr.rows; ++y) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < bgr.cols; ++x) color(x, y) = Rgb8{row[x][2], row[x][1], row[x][0]};
  }
  return color;
}

void write_depth_png(const std::string& path, const DepthImage& depth, double scale) {
  if (depth.empty()) throw Error(path + ": cannot write an empty depth image");
  if (!(scale > 0.0) || !std::isfinite(scale))
    throw Error(path + ": depth scale must be a positive number, got " + std::to_string(scale));
  cv::Mat raw(depth.height(), depth.width(), CV_16UC1);
  for (int y = 0; y < depth.height(); ++y) {
    std::uint16_t* row = raw.ptr<std::uint16_t>(y);
    for (int x = 0; x < depth.width(); ++x) {
      const double d = depth(x, y);
      const double r = std::isfinite(d) && d > 0.0 ? std::round(d * scale) : 0.0;
      row[x] = (r >= 1.0 && r <= 65535.0) ? std::uint16_t(r) : 0;
    }
  }
  write_path_atomically(path, [&](const std::string& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp, raw);
    } catch (const cv::Exception& e) {
      throw Error(path + ": cannot write depth image (" + e.msg + ")");
    }
    if (!ok) throw Error(path + ": cannot write depth image");
  });
}

void write_color_png(const std::string& path, const ColorImage& color) {
  if (color.empty()) throw Error(path + ": cannot write an empty colour image");
  cv::Mat bgr(color.height(), color.width(), CV_8UC3);
  for (int y = 0; y < color.height(); ++y) {
    cv::Vec3b* row = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < color.width(); ++x) {
      const Rgb8 p = color(x, y);
      row[x] = cv::Vec3b(p.b, p.g, p.r);
    }
  }
  write_path_atomically(path, [&](const std::string& tmp) {
    bool ok = false;
    try {
      ok = cv::imwrite(tmp, bgr);
    } catch (const cv::Exception& e) {
      throw Error(path + ": cannot write colour image (" + e.msg + ")");
    }
    if (!ok) throw Error(path + ": cannot write colour image");
  });
}

}  // namespace hf
