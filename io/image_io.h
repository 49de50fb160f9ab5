// Loading and writing the depth and colour images of RGB-D datasets.
//
// Depth in memory is hf::DepthImage: float metres, 0 = no measurement, never NaN or inf (core/image.h).
// On disk depth is either a 16-bit single-channel PNG holding round(depth_m * scale) (TUM: scale 5000,
// 7-Scenes: 1000 = millimetres; raw 0 means "no measurement") or a 32-bit float single-channel image (TIFF,
// EXR where OpenCV supports it) already in metres, whose non-finite and non-positive values are stored as 0.
// Colour in memory is hf::ColorImage (RGB, R first). OpenCV decodes to BGR; these functions swap the channels,
// so callers never see BGR.
//
// Loaders read only regular files of at most kMaxImageFileBytes (core/bounded_read.h: a FIFO or a device is
// refused, never read) and decode by content, not by name: content whose format contradicts the extension (a JPEG
// renamed .png) is refused, and so is a decoded type that does not fit the role (a colour image as depth, a 16-bit
// single-channel depth map as colour). Writers encode PNG in memory whatever the name says and write the bytes
// with write_file_atomically (core/atomic_file.h).
// Failures: every loader throws hf::Error naming the file for a missing, unreadable, truncated or undecodable
// image, or one with an unsupported pixel type (e.g. an 8-bit "depth" image). The dataset readers turn these
// into bad_frame results; nothing here prints or aborts.
// Thread-safety: all functions are reentrant (they share no state); OpenCV's codecs are thread-safe.
#pragma once

#include <cstdint>
#include <string>

#include "core/image.h"

namespace hf {

struct DepthDecoding {
  // Raw 16-bit units per metre: depth_m = raw / scale. TUM 5000, 7-Scenes 1000. Ignored for float images.
  double scale = 5000.0;
  // A raw value that also means "no measurement" besides 0 (7-Scenes marks invalid pixels 65535); -1 = none.
  int invalid_raw = -1;
};

// Loads a depth image (16-bit PNG or 32-bit float image) as metres. Throws hf::Error (see above) and for a
// non-positive or non-finite scale.
DepthImage load_depth(const std::string& path, const DepthDecoding& decoding = {});

// Loads a colour image (PNG, JPEG, anything OpenCV reads; grey images are expanded, 16-bit colour reduced to
// 8 bits, alpha dropped) as RGB. Throws hf::Error (see above).
ColorImage load_color(const std::string& path);

// Converts raw 16-bit depth samples (row-major, width*height of them) to metres; exposed for tests and for
// callers that decode themselves.
DepthImage depth_from_raw16(const std::uint16_t* raw, int width, int height, const DepthDecoding& decoding = {});

// Writes a 16-bit single-channel PNG of round(depth_m * scale), atomically (temporary file + rename). Pixels
// that are 0, negative or non-finite are written as 0 ("no measurement"); so are depths beyond the format's
// range (raw > 65535, e.g. 13.1 m at scale 5000), which a real sensor cannot report either.
// Throws hf::Error naming the file when the image is empty, the scale is not positive, or writing fails.
void write_depth_png(const std::string& path, const DepthImage& depth, double scale = 5000.0);

// Writes an 8-bit 3-channel PNG (the file stores what OpenCV expects; reading it with load_color gives back the
// same RGB values), atomically. Throws hf::Error naming the file when the image is empty or writing fails.
void write_color_png(const std::string& path, const ColorImage& color);

}  // namespace hf
