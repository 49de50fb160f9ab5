// Image sizes read from an encoded image's header, so a small file that promises a huge image is refused before
// it is decoded (a 760 KB PNG can state 20000 x 20000 16-bit pixels: 800 MB and seconds of decoding).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "io/image_io.h"

namespace hf {

// The largest image decoded when no size is expected: 64 Mpx (8192 x 8192; 128 MiB as 16-bit depth).
inline constexpr long long kMaxImagePixels = 1LL << 26;

// The size a caller expects (a dataset's camera); 0 x 0 = any size up to kMaxImagePixels.
struct ExpectedImageSize {
  int width = 0, height = 0;
};

// The size an encoded image's header states, read without decoding: PNG (IHDR), JPEG (the first SOF marker),
// TIFF (the first IFD) and BMP; nullopt for other formats (EXR: OpenCV's own 2^30-pixel limit is the only one) or
// a header too short to say. Reads only within `bytes`, whatever they hold.
struct ImageHeaderSize {
  std::uint32_t width = 0, height = 0;
  const char* source = "";  // "PNG IHDR", "JPEG SOF", ... for messages
};
std::optional<ImageHeaderSize> image_header_size(const std::string& bytes);

// load_depth / load_color (io/image_io.h) with the header's size checked before decoding: a size other than
// `expected`, or beyond kMaxImagePixels, is an hf::Error naming the file ("PATH: depth image is 20000x20000 (its
// PNG IHDR) but the camera is 640x480; not decoded"). The two-argument forms check against kMaxImagePixels only.
DepthImage load_depth(const std::string& path, const DepthDecoding& decoding, const ExpectedImageSize& expected);
ColorImage load_color(const std::string& path, const ExpectedImageSize& expected);

}  // namespace hf
