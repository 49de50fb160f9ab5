#include "io/image_io.h"

#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <optional>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <ostream>
#include <vector>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "io/image_header.h"

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

std::uint32_t image_io_be32(const std::string& b, size_t at) {
  return std::uint32_t(std::uint8_t(b[at])) << 24 | std::uint32_t(std::uint8_t(b[at + 1])) << 16 |
         std::uint32_t(std::uint8_t(b[at + 2])) << 8 | std::uint32_t(std::uint8_t(b[at + 3]));
}
std::uint32_t image_io_u16(const std::string& b, size_t at, bool big_endian) {
  const std::uint32_t x = std::uint8_t(b[at]), y = std::uint8_t(b[at + 1]);
  return big_endian ? (x << 8 | y) : (y << 8 | x);
}
std::uint32_t image_io_u32(const std::string& b, size_t at, bool big_endian) {
  const std::uint32_t lo = image_io_u16(b, at, big_endian), hi = image_io_u16(b, at + 2, big_endian);
  return big_endian ? (lo << 16 | hi) : (hi << 16 | lo);
}

// Width and height from a JPEG's first SOF marker: markers are walked by their lengths, each step moving forward,
// so the walk ends within the bytes whatever they hold.
std::optional<ImageHeaderSize> jpeg_header_size(const std::string& b) {
  size_t at = 2;  // after SOI
  while (at + 4 <= b.size()) {
    if (std::uint8_t(b[at]) != 0xff) return std::nullopt;
    const std::uint8_t marker = std::uint8_t(b[at + 1]);
    if (marker == 0xff) {  // fill byte
      ++at;
      continue;
    }
    if (marker == 0x01 || (marker >= 0xd0 && marker <= 0xd8)) {  // markers without a length
      at += 2;
      continue;
    }
    const size_t length = image_io_u16(b, at + 2, true);
    const bool sof = marker >= 0xc0 && marker <= 0xcf && marker != 0xc4 && marker != 0xc8 && marker != 0xcc;
    if (sof) {
      if (at + 9 > b.size()) return std::nullopt;
      return ImageHeaderSize{image_io_u16(b, at + 7, true), image_io_u16(b, at + 5, true), "JPEG SOF"};
    }
    if (length < 2) return std::nullopt;
    at += 2 + length;
  }
  return std::nullopt;
}

// Width and height from the first IFD of a TIFF (tags 256 ImageWidth and 257 ImageLength, SHORT or LONG).
std::optional<ImageHeaderSize> tiff_header_size(const std::string& b) {
  if (b.size() < 8) return std::nullopt;
  const bool big = b[0] == 'M';
  const size_t ifd = image_io_u32(b, 4, big);
  if (ifd + 2 > b.size()) return std::nullopt;
  const size_t entries = image_io_u16(b, ifd, big);
  std::optional<std::uint32_t> width, height;
  for (size_t k = 0; k < entries && ifd + 2 + 12 * (k + 1) <= b.size(); ++k) {
    const size_t e = ifd + 2 + 12 * k;
    const std::uint32_t tag = image_io_u16(b, e, big), type = image_io_u16(b, e + 2, big);
    if ((tag != 256 && tag != 257) || (type != 3 && type != 4)) continue;
    const std::uint32_t value = type == 3 ? image_io_u16(b, e + 8, big) : image_io_u32(b, e + 8, big);
    (tag == 256 ? width : height) = value;
  }
  if (!width || !height) return std::nullopt;
  return ImageHeaderSize{*width, *height, "TIFF IFD"};
}

// Reads only a regular file of bounded size (core/bounded_read.h), refuses content whose format contradicts the
// name (a JPEG renamed .png is a different, lossy recording), checks the size its header states against
// `expected` (or kMaxImagePixels) before decoding, and decodes the bytes as they are (no conversion, so the caller
// can check channels and bit depth). cv::imdecode may throw cv::Exception on corrupt data; catching it keeps the
// failure a single hf::Error naming the file.
cv::Mat read_image(const std::string& path, const char* what, const ExpectedImageSize& expected) {
  const std::string bytes = read_regular_file(path, std::string(what) + " image", kMaxImageFileBytes);
  const char* content = format_of_content(bytes);
  const char* named = format_of_name(path);
  if (content && named && std::strcmp(content, named) != 0)
    throw Error(path + ": " + what + " image holds " + content + " data but its name says " + named +
                " (a renamed file?)");
  // A 760 KB PNG can promise 20000 x 20000 16-bit pixels: 800 MB and seconds of decoding before any size check.
  if (const std::optional<ImageHeaderSize> size = image_header_size(bytes)) {
    const std::string stated = std::string(what) + " image is " + std::to_string(size->width) + "x" +
                               std::to_string(size->height) + " (its " + size->source + ")";
    const bool other_size =
        size->width != std::uint32_t(expected.width) || size->height != std::uint32_t(expected.height);
    if (expected.width > 0 && other_size)
      throw Error(path + ": " + stated + " but the camera is " + std::to_string(expected.width) + "x" +
                  std::to_string(expected.height) + "; not decoded");
    if (double(size->width) * double(size->height) > double(kMaxImagePixels))
      throw Error(path + ": " + stated + ", more than the " + std::to_string(kMaxImagePixels) +
                  "-pixel limit; not decoded");
  }
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

std::optional<ImageHeaderSize> image_header_size(const std::string& bytes) {
  const char* format = format_of_content(bytes);
  if (!format) return std::nullopt;
  const std::string f = format;
  if (f == "PNG") {  // signature, then the IHDR chunk: length, "IHDR", width, height (big-endian)
    if (bytes.size() < 24 || bytes.compare(12, 4, "IHDR") != 0) return std::nullopt;
    return ImageHeaderSize{image_io_be32(bytes, 16), image_io_be32(bytes, 20), "PNG IHDR"};
  }
  if (f == "JPEG") return jpeg_header_size(bytes);
  if (f == "TIFF") return tiff_header_size(bytes);
  if (f == "BMP") {  // BITMAPINFOHEADER: width, then height (negative: top-down), little-endian
    if (bytes.size() < 26) return std::nullopt;
    const auto height = std::int32_t(image_io_u32(bytes, 22, false));
    return ImageHeaderSize{image_io_u32(bytes, 18, false),
                           height < 0 ? std::uint32_t(0) - std::uint32_t(height) : std::uint32_t(height), "BMP header"};
  }
  return std::nullopt;  // EXR: OpenCV's own limit (2^30 pixels) is the only one
}

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

DepthImage load_depth(const std::string& path, const DepthDecoding& decoding, const ExpectedImageSize& expected) {
  if (!(decoding.scale > 0.0) || !std::isfinite(decoding.scale))
    throw Error(path + ": depth scale must be a positive number, got " + std::to_string(decoding.scale));
  const cv::Mat image = read_image(path, "depth", expected);
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

DepthImage load_depth(const std::string& path, const DepthDecoding& decoding) { return load_depth(path, decoding, {}); }

ColorImage load_color(const std::string& path) { return load_color(path, ExpectedImageSize{}); }

ColorImage load_color(const std::string& path, const ExpectedImageSize& expected) {
  const cv::Mat image = read_image(path, "colour", expected);
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
