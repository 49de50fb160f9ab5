#include "io/pixel_formats.h"

#include <algorithm>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "core/error.h"

namespace hf {
namespace {

size_t packed_row_bytes(PixelFormat f, int width) {
  switch (f) {
    case PixelFormat::yuyv:
    case PixelFormat::uyvy:
    case PixelFormat::z16: return size_t(width) * 2;
    case PixelFormat::rgb24:
    case PixelFormat::bgr24: return size_t(width) * 3;
    case PixelFormat::xbgr32:
    case PixelFormat::xrgb32: return size_t(width) * 4;
    case PixelFormat::nv12: return size_t(width);
    case PixelFormat::mjpeg: return 0;
  }
  return 0;
}

// Checks that rows of `stride` bytes hold the image and that the buffer holds `rows` of them (the last one may be
// just the packed row); returns the stride to use.
size_t check_buffer(PixelFormat f, size_t bytes, int width, int height, size_t stride, size_t rows) {
  if (width <= 0 || height <= 0)
    throw Error(to_string(f) + " frame: invalid size " + std::to_string(width) + "x" + std::to_string(height));
  const size_t packed = packed_row_bytes(f, width);
  if (stride == 0) stride = packed;
  if (stride < packed)
    throw Error(to_string(f) + " frame: row stride " + std::to_string(stride) + " bytes is shorter than a " +
                std::to_string(width) + "-pixel row (" + std::to_string(packed) + " bytes)");
  const size_t need = stride * (rows - 1) + packed;
  if (bytes < need)
    throw Error(to_string(f) + " frame of " + std::to_string(bytes) + " bytes, expected at least " +
                std::to_string(need) + " for " + std::to_string(width) + "x" + std::to_string(height) +
                " (stride " + std::to_string(stride) + ")");
  return stride;
}

std::uint8_t clamp8(int v) { return std::uint8_t(std::clamp(v, 0, 255)); }

// BT.601 limited range (Y 16-235, C 16-240) in integer arithmetic: the coefficients of the standard scaled by 256.
Rgb8 ycbcr_to_rgb(int y, int u, int v) {
  const int c = y - 16, d = u - 128, e = v - 128;
  return {clamp8((298 * c + 409 * e + 128) >> 8), clamp8((298 * c - 100 * d - 208 * e + 128) >> 8),
          clamp8((298 * c + 516 * d + 128) >> 8)};
}

ColorImage decode_422(PixelFormat f, const std::uint8_t* data, size_t bytes, int w, int h, size_t stride) {
  if (w % 2) throw Error(to_string(f) + " frame: width " + std::to_string(w) + " is odd (4:2:2 pairs pixels)");
  stride = check_buffer(f, bytes, w, h, stride, size_t(h));
  const bool yuyv = f == PixelFormat::yuyv;
  ColorImage out(w, h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* row = data + size_t(y) * stride;
    for (int x = 0; x < w; x += 2, row += 4) {
      const int y0 = yuyv ? row[0] : row[1], y1 = yuyv ? row[2] : row[3];
      const int u = yuyv ? row[1] : row[0], v = yuyv ? row[3] : row[2];
      out(x, y) = ycbcr_to_rgb(y0, u, v);
      out(x + 1, y) = ycbcr_to_rgb(y1, u, v);
    }
  }
  return out;
}

ColorImage decode_nv12(const std::uint8_t* data, size_t bytes, int w, int h, size_t stride) {
  if (w % 2 || h % 2)
    throw Error("nv12 frame: size " + std::to_string(w) + "x" + std::to_string(h) + " is odd (4:2:0 halves both)");
  // Luma rows, then h / 2 chroma rows of the same stride.
  stride = check_buffer(PixelFormat::nv12, bytes, w, h, stride, size_t(h) + size_t(h) / 2);
  const std::uint8_t* chroma = data + stride * size_t(h);
  ColorImage out(w, h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* luma = data + size_t(y) * stride;
    const std::uint8_t* uv = chroma + size_t(y / 2) * stride;
    for (int x = 0; x < w; ++x) out(x, y) = ycbcr_to_rgb(luma[x], uv[(x / 2) * 2], uv[(x / 2) * 2 + 1]);
  }
  return out;
}

ColorImage decode_packed(PixelFormat f, const std::uint8_t* data, size_t bytes, int w, int h, size_t stride) {
  stride = check_buffer(f, bytes, w, h, stride, size_t(h));
  const int step = (f == PixelFormat::rgb24 || f == PixelFormat::bgr24) ? 3 : 4;
  const bool r_first = f == PixelFormat::rgb24 || f == PixelFormat::xbgr32;
  ColorImage out(w, h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* p = data + size_t(y) * stride;
    for (int x = 0; x < w; ++x, p += step)
      out(x, y) = r_first ? Rgb8{p[0], p[1], p[2]} : Rgb8{p[2], p[1], p[0]};
  }
  return out;
}

ColorImage decode_mjpeg(const std::uint8_t* data, size_t bytes, int w, int h) {
  if (bytes == 0 || bytes > size_t(64) << 20) throw Error("mjpeg frame: " + std::to_string(bytes) + " bytes");
  const cv::Mat buffer(1, int(bytes), CV_8UC1, const_cast<std::uint8_t*>(data));
  cv::Mat bgr;
  try {
    bgr = cv::imdecode(buffer, cv::IMREAD_COLOR);
  } catch (const cv::Exception&) {
    bgr = cv::Mat();
  }
  if (bgr.empty()) throw Error("mjpeg frame: not a decodable JPEG (" + std::to_string(bytes) + " bytes)");
  if (bgr.cols != w || bgr.rows != h)
    throw Error("mjpeg frame: JPEG is " + std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows) +
                ", the stream is " + std::to_string(w) + "x" + std::to_string(h));
  ColorImage out(w, h);
  for (int y = 0; y < h; ++y) {
    const cv::Vec3b* row = bgr.ptr<cv::Vec3b>(y);
    for (int x = 0; x < w; ++x) out(x, y) = {row[x][2], row[x][1], row[x][0]};
  }
  return out;
}

}  // namespace

std::string to_string(PixelFormat f) {
  switch (f) {
    case PixelFormat::yuyv: return "yuyv";
    case PixelFormat::uyvy: return "uyvy";
    case PixelFormat::rgb24: return "rgb24";
    case PixelFormat::bgr24: return "bgr24";
    case PixelFormat::xbgr32: return "xbgr32";
    case PixelFormat::xrgb32: return "xrgb32";
    case PixelFormat::nv12: return "nv12";
    case PixelFormat::mjpeg: return "mjpeg";
    case PixelFormat::z16: return "z16";
  }
  return "?";
}

std::optional<PixelFormat> pixel_format_from_v4l2(std::uint32_t code) {
  if (code == fourcc('Y', 'U', 'Y', 'V')) return PixelFormat::yuyv;
  if (code == fourcc('U', 'Y', 'V', 'Y')) return PixelFormat::uyvy;
  if (code == fourcc('R', 'G', 'B', '3')) return PixelFormat::rgb24;
  if (code == fourcc('B', 'G', 'R', '3')) return PixelFormat::bgr24;
  if (code == fourcc('X', 'R', '2', '4')) return PixelFormat::xrgb32;
  if (code == fourcc('X', 'B', '2', '4')) return PixelFormat::xbgr32;
  if (code == fourcc('N', 'V', '1', '2')) return PixelFormat::nv12;
  if (code == fourcc('M', 'J', 'P', 'G') || code == fourcc('J', 'P', 'E', 'G')) return PixelFormat::mjpeg;
  if (code == fourcc('Z', '1', '6', ' ')) return PixelFormat::z16;
  return std::nullopt;
}

std::string fourcc_text(std::uint32_t code) {
  std::string s;
  for (int i = 0; i < 4; ++i) {
    const char c = char((code >> (8 * i)) & 0xff);
    s += (c >= 32 && c < 127) ? c : '?';
  }
  return s;
}

ColorImage decode_color(PixelFormat f, const std::uint8_t* data, size_t bytes, int w, int h, size_t stride) {
  if (!data && bytes) throw Error(to_string(f) + " frame: no data");
  switch (f) {
    case PixelFormat::yuyv:
    case PixelFormat::uyvy: return decode_422(f, data, bytes, w, h, stride);
    case PixelFormat::rgb24:
    case PixelFormat::bgr24:
    case PixelFormat::xbgr32:
    case PixelFormat::xrgb32: return decode_packed(f, data, bytes, w, h, stride);
    case PixelFormat::nv12: return decode_nv12(data, bytes, w, h, stride);
    case PixelFormat::mjpeg: return decode_mjpeg(data, bytes, w, h);
    case PixelFormat::z16: break;
  }
  throw Error("z16 is a depth format, not a colour one");
}

DepthImage decode_z16(const std::uint8_t* data, size_t bytes, int w, int h, size_t stride, double depth_unit_m) {
  if (!(depth_unit_m > 0.0) || depth_unit_m > 1.0)
    throw Error("z16 frame: depth unit " + std::to_string(depth_unit_m) + " m is not in (0, 1]");
  stride = check_buffer(PixelFormat::z16, bytes, w, h, stride, size_t(h));
  DepthImage out(w, h);
  for (int y = 0; y < h; ++y) {
    const std::uint8_t* p = data + size_t(y) * stride;
    for (int x = 0; x < w; ++x, p += 2) out(x, y) = float(double(p[0] | (p[1] << 8)) * depth_unit_m);
  }
  return out;
}

}  // namespace hf
