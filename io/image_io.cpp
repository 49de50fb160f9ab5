#include "io/image_io.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <vector>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"

namespace hf {
namespace {

// The image format a file's first bytes announce; decoding goes by content, never by name.
const char* format_of_content(const std::string& bytes) {
  auto starts = [&](const char* magic, size_t n) { return bytes.size() >= n && bytes.compare(0, n, magic, n) == 0; };
  if (starts("\x89PNG\r\n\x1a\n", 8)) return "PNG";
  if (starts("\xff\xd8\xff", 3)) return "JPEG";
  if (starts("II*\0", 4) || starts("MM\0*", 4)) return "TIFF";
  if (starts("v/1\x01", 4)) return "EXR";
  if (starts("BM", 2)) return "BMP";
  return nullptr;
}

// The format a file name promises, or nullptr for a name that promises none we check.
const char* format_of_name(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".png") return "PNG";
  if (ext == ".jpg" || ext == ".jpeg") return "JPEG";
  if (ext == ".tif" || ext == ".tiff") return "TIFF";
  if (ext == ".exr") return "EXR";
  if (ext == ".bmp") return "BMP";
  return nullptr;
}

// Reads only a regular file of bounded size (core/bounded_read.h), refuses content whose format contradicts the
// name (a JPEG renamed .png is a different, lossy recording), and decodes the bytes as they are (no conversion, so
// the caller can check channels and bit depth). cv::imdecode may throw cv::Exception on corrupt data; catching it
// keeps the failure a single hf::Error naming the file.
cv::Mat read_image(const std::string& path, const char* what) {
  const std::string bytes = read_regular_file(path, std::string(what) + " image", kMaxImageFileBytes);
  const char* content = format_of_content(bytes);
  const char* named = format_of_name(path);
  if (content && named && std::strcmp(content, named) != 0)
    throw Error(path + ": " + what + " image holds " + content + " data but its name says " + named +
                " (a renamed file?)");
  cv::Mat image;
  try {
    const cv::Mat buffer(1, int(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
    if (!bytes.empty()) image = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot decode " + what + " image (" + e.msg + ")");
  }
  if (image.empty()) throw Error(path + ": cannot decode " + what + " image (truncated or not an image)");
  return image;
}

// PNG for the writers: the format is the function's, not the file name's (so "--plot out" works too).
std::vector<unsigned char> encode_png(const cv::Mat& image, const std::string& path, const char* what) {
  std::vector<unsigned char> png;
  bool ok = false;
  try {
    ok = cv::imencode(".png", image, png);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot encode " + what + " image (" + e.msg + ")");
  }
  if (!ok) throw Error(path + ": cannot encode " + what + " image");
  return png;
}

void write_bytes(const std::string& path, const std::vector<unsigned char>& bytes) {
  write_file_atomically(
      path, [&](std::ostream& out) { out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size())); },
      true);
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
  const cv::Mat image = read_image(path, "depth");
  if (image.channels() != 1)
    throw Error(path + ": expected a single-channel depth image, got " + std::to_string(image.channels()) + " channels");
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
  const cv::Mat image = read_image(path, "colour");
  const int channels = image.channels();
  if (image.depth() != CV_8U && image.depth() != CV_16U)
    throw Error(path + ": expected an 8- or 16-bit colour image, got " + std::to_string(image.elemSize1() * 8) +
                "-bit samples");
  if (channels == 1 && image.depth() == CV_16U)
    throw Error(path + ": expected a colour image, got a 16-bit single-channel image (a depth map?)");
  if (channels != 1 && channels != 3 && channels != 4)
    throw Error(path + ": expected a grey, colour or colour+alpha image, got " + std::to_string(channels) + " channels");
  cv::Mat eight = image;
  if (image.depth() == CV_16U) image.convertTo(eight, CV_8U, 1.0 / 256.0);  // as cv::IMREAD_COLOR reduces 16 bits
  ColorImage color(eight.cols, eight.rows);
  for (int y = 0; y < eight.rows; ++y) {
    const std::uint8_t* row = eight.ptr<std::uint8_t>(y);
    for (int x = 0; x < eight.cols; ++x) {
      const std::uint8_t* p = row + size_t(x) * size_t(channels);
      color(x, y) = channels == 1 ? Rgb8{p[0], p[0], p[0]} : Rgb8{p[2], p[1], p[0]};  // OpenCV stores BGR(A)
    }
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
  write_bytes(path, encode_png(raw, path, "depth"));
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
  write_bytes(path, encode_png(bgr, path, "colour"));
}

}  // namespace hf
