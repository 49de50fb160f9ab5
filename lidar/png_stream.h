// An RGB8 PNG written row by row (the tiled merge writes rasters larger than memory): IHDR, the rows deflated as
// they come (filter 0, zlib level 6) into IDAT chunks of exactly 64 KiB (the last shorter), IEND. The bytes depend
// only on the rows, not on how the caller groups them, so a single run and a merge write the same file.
// Failures (cannot open, disk full, too many or too few rows at close) throw hf::Error naming the file; the
// caller owns atomicity (write_path_atomically).
#pragma once

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include <zlib.h>

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
  void deflate_into_chunks(const unsigned char* data, size_t size, int flush);
  void chunk(const char type[4], const unsigned char* data, size_t size);

  std::string path_;
  int width_ = 0, height_ = 0, rows_ = 0;
  std::ofstream out_;
  z_stream z_{};
  bool z_open_ = false;
  std::vector<unsigned char> line_, idat_;
};

}  // namespace hf::lidar
