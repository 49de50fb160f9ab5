// The libcamera back-end's frame path, kept apart from io/libcamera_capture.cpp so it builds (and is tested)
// without libcamera.
#include <cstring>

#include "core/error.h"
#include "io/libcamera_capture.h"

namespace hf {

std::optional<PixelFormat> pixel_format_from_libcamera(std::uint32_t code) {
  if (code == fourcc('Y', 'U', 'Y', 'V')) return PixelFormat::yuyv;
  if (code == fourcc('U', 'Y', 'V', 'Y')) return PixelFormat::uyvy;
  if (code == fourcc('R', 'G', '2', '4')) return PixelFormat::bgr24;  // RGB888: B, G, R in memory
  if (code == fourcc('B', 'G', '2', '4')) return PixelFormat::rgb24;  // BGR888: R, G, B in memory
  if (code == fourcc('X', 'R', '2', '4')) return PixelFormat::xrgb32;  // XRGB8888: B, G, R, X
  if (code == fourcc('X', 'B', '2', '4')) return PixelFormat::xbgr32;  // XBGR8888: R, G, B, X
  if (code == fourcc('N', 'V', '1', '2')) return PixelFormat::nv12;
  if (code == fourcc('M', 'J', 'P', 'G')) return PixelFormat::mjpeg;
  return std::nullopt;
}

ColorImage libcamera_planes_to_rgb(std::uint32_t code, const std::vector<PlaneView>& planes, int width, int height,
                                   size_t stride) {
  const std::optional<PixelFormat> format = pixel_format_from_libcamera(code);
  if (!format) throw Error("libcamera frame: pixel format " + fourcc_text(code) + " is not one hashfusion reads");
  if (planes.size() == 1) return decode_color(*format, planes[0].data, planes[0].bytes, width, height, stride);
  std::vector<std::uint8_t> joined;
  for (const PlaneView& p : planes) {
    if (!p.data && p.bytes) throw Error("libcamera frame: a plane without data");
    joined.insert(joined.end(), p.data, p.data + p.bytes);
  }
  return decode_color(*format, joined.data(), joined.size(), width, height, stride);
}

}  // namespace hf
