// Camera pixel formats to hashfusion images: the one place where V4L2 and libcamera buffers become RGB colour and
// metric depth, so both back-ends (io/v4l2_capture.h, io/libcamera_capture.h) decode the same way.
//
// Layouts (bytes in memory order; `stride` = bytes per row, >= the packed row, 0 = packed):
//   yuyv    Y0 U Y1 V per two pixels (V4L2 YUYV, libcamera YUYV); BT.601 limited range, the UVC default
//   uyvy    U Y0 V Y1
//   rgb24   R G B          (V4L2 RGB3, libcamera BGR888: DRM names the little-endian word)
//   bgr24   B G R          (V4L2 BGR3, libcamera RGB888)
//   xbgr32  R G B X        (libcamera XBGR8888)
//   xrgb32  B G R X        (libcamera XRGB8888, V4L2 XR24)
//   nv12    W*H luma plane (rows of `stride`), then W*H/2 interleaved U V at half resolution, same stride
//   mjpeg   one JPEG image (UVC MJPG; Huffman tables may be missing, libjpeg supplies the standard ones)
//   z16     16-bit little-endian depth units (RealSense UVC Z16), times depth_unit_m
// Failures: hf::Error naming the format and what is wrong (buffer shorter than the image, odd width for 4:2:2,
// undecodable or wrongly sized JPEG). Never reads past `bytes`. Reentrant.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include "core/image.h"

namespace hf {

// The V4L2 / DRM four-character code of a pixel format ('Y','U','Y','V' -> V4L2_PIX_FMT_YUYV): a, b, c, d from the
// least significant byte up.
constexpr std::uint32_t fourcc(char a, char b, char c, char d) {
  return std::uint32_t(std::uint8_t(a)) | (std::uint32_t(std::uint8_t(b)) << 8) |
         (std::uint32_t(std::uint8_t(c)) << 16) | (std::uint32_t(std::uint8_t(d)) << 24);
}

enum class PixelFormat { yuyv, uyvy, rgb24, bgr24, xbgr32, xrgb32, nv12, mjpeg, z16 };

std::string to_string(PixelFormat format);
// The format a V4L2 fourcc (e.g. v4l2_fourcc('Y','U','Y','V')) names, or nullopt when we cannot decode it.
std::optional<PixelFormat> pixel_format_from_v4l2(std::uint32_t fourcc);
// The four characters of a fourcc, for messages ("YUYV", "Z16 ").
std::string fourcc_text(std::uint32_t fourcc);

// Colour formats (all but z16) to RGB. width, height > 0.
ColorImage decode_color(PixelFormat format, const std::uint8_t* data, size_t bytes, int width, int height,
                        size_t stride = 0);
// z16 to metres (0 stays 0 = no measurement).
DepthImage decode_z16(const std::uint8_t* data, size_t bytes, int width, int height, size_t stride,
                      double depth_unit_m);

}  // namespace hf
