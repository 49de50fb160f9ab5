// An RGB8 PNG written row by row (the tiled merge writes rasters larger than memory), through libpng's row writer
// (png_write_row): IHDR, the rows deflated as they come (filter None, zlib level 6) into IDAT chunks of libpng's
// 64 KiB compression buffer (the last shorter), IEND. The bytes depend only on the rows, not on how the caller
// groups them, so a single run and a merge write the same file.
// Failures (cannot open, disk full, a libpng error, too many or too few rows at close) throw hf::Error naming the
// file; the caller owns atomicity (write_path_atomically). Not thread-safe; one writer per file.
#pragma once

#include <memory>
#include <string>

#include "core/image.h"

namespace hf::lidar {

class PngStream {
 public:
  PngStream(const std::string& path, int width, int height);  // throws for a non-positive size or an unopenable path
  ~PngStream();
  PngStream(const PngStream&) = delete;
  PngStream& operator=(const PngStream&) = delete;

  void row(const Rgb8* pixels);  // `width` pixels, rows top to bottom
  void close();                  // after exactly `height` rows

 private:
  struct Libpng;  // libpng's write state and the file (png_stream.cpp); keeps png.h out of this header
  std::string path_;
  int width_ = 0, height_ = 0, rows_ = 0;
  std::unique_ptr<Libpng> png_;
};

}  // namespace hf::lidar
