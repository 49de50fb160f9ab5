// Fuzzes the camera-buffer decoders (io/pixel_formats.h), which read whatever a device or a driver hands over:
// the first two bytes choose the format and a small size, the rest is the buffer. Any input either decodes into an
// image of exactly the requested size or throws hf::Error; a crash, a read past the buffer (ASan) or another
// exception is a finding.
#include <cstddef>
#include <cstdint>
#include <cstdlib>

#include "core/error.h"
#include "io/libcamera_capture.h"
#include "io/pixel_formats.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const auto format = hf::PixelFormat(data[0] % 9);
  const int width = 1 + (data[1] & 15), height = 1 + (data[1] >> 4);
  const std::uint8_t* buffer = data + 2;
  const size_t bytes = size - 2;
  const size_t stride = (data[0] / 9) % 4 == 0 ? 0 : size_t(width) * 4 + (data[0] / 36);
  try {
    if (format == hf::PixelFormat::z16) {
      const hf::DepthImage d = hf::decode_z16(buffer, bytes, width, height, stride, 0.001);
      if (d.width() != width || d.height() != height) std::abort();
    } else {
      const hf::ColorImage c = hf::decode_color(format, buffer, bytes, width, height, stride);
      if (c.width() != width || c.height() != height) std::abort();
    }
  } catch (const hf::Error&) {
  }
  // The libcamera path: the same bytes as two planes split in the middle.
  try {
    const std::uint32_t nv12 = 0x3231564e;
    const hf::ColorImage c =
        hf::libcamera_planes_to_rgb(nv12, {{buffer, bytes / 2}, {buffer + bytes / 2, bytes - bytes / 2}}, width,
                                    height, 0);
    if (c.width() != width) std::abort();
  } catch (const hf::Error&) {
  }
  return 0;
}
