#include "lidar/png_stream.h"

#include <cstring>

#include "core/error.h"

namespace hf::lidar {
namespace {
constexpr size_t kIdatBytes = 64 * 1024;
}  // namespace

static_assert(sizeof(Rgb8) == 3, "rows are copied as packed RGB");

PngStream::PngStream(const std::string& path, int width, int height) : path_(path), width_(width), height_(height) {
  if (width <= 0 || height <= 0) throw Error(path + ": cannot write an empty PNG");
  out_.open(path, std::ios::binary | std::ios::trunc);
  if (!out_) throw Error(path + ": cannot open for writing");
  static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  out_.write(reinterpret_cast<const char*>(signature), 8);
  // 8 bits, RGB, deflate, adaptive filtering (every row uses filter 0), no interlace.
  unsigned char ihdr[13] = {0, 0, 0, 0, 0, 0, 0, 0, 8, 2, 0, 0, 0};
  for (int i = 0; i < 4; ++i)
    ihdr[i] = static_cast<unsigned char>(std::uint32_t(width) >> (24 - 8 * i)), ihdr[4 + i] = static_cast<unsigned char>(std::uint32_t(height) >> (24 - 8 * i));
  chunk("IHDR", ihdr, sizeof ihdr);
  if (deflateInit(&z_, 6) != Z_OK) throw Error(path + ": zlib cannot start");
  z_open_ = true;
  line_.resize(1 + size_t(width) * 3);
}

PngStream::~PngStream() {
  if (z_open_) deflateEnd(&z_);
}

void PngStream::chunk(const char type[4], const unsigned char* data, size_t size) {
  unsigned char head[8], tail[4];
  const auto be32 = [](unsigned char* at, std::uint32_t x) {
    for (int i = 0; i < 4; ++i) at[i] = static_cast<unsigned char>(x >> (24 - 8 * i));
  };
  be32(head, std::uint32_t(size));
  std::memcpy(head + 4, type, 4);
  std::uint32_t crc = static_cast<std::uint32_t>(crc32(0, head + 4, 4));
  if (size) crc = static_cast<std::uint32_t>(crc32(crc, data, static_cast<uInt>(size)));
  be32(tail, crc);
  out_.write(reinterpret_cast<const char*>(head), 8);
  if (size) out_.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out_.write(reinterpret_cast<const char*>(tail), 4);
  if (!out_) throw Error(path_ + ": write failed (disk full?)");
}

// Deflates `data` and emits every full 64 KiB of compressed bytes as one IDAT chunk.
void PngStream::deflate_into_chunks(const unsigned char* data, size_t size, int flush) {
  z_.next_in = const_cast<Bytef*>(data);
  z_.avail_in = static_cast<uInt>(size);
  unsigned char buffer[16384];
  int rc = Z_OK;
  do {
    z_.next_out = buffer;
    z_.avail_out = sizeof buffer;
    rc = deflate(&z_, flush);
    if (rc == Z_STREAM_ERROR) throw Error(path_ + ": zlib failed");
    idat_.insert(idat_.end(), buffer, buffer + (sizeof buffer - z_.avail_out));
    while (idat_.size() >= kIdatBytes) {
      chunk("IDAT", idat_.data(), kIdatBytes);
      idat_.erase(idat_.begin(), idat_.begin() + kIdatBytes);
    }
  } while (z_.avail_out == 0 || (flush == Z_FINISH && rc != Z_STREAM_END));
}

void PngStream::row(const Rgb8* pixels) {
  if (rows_ >= height_) throw Error(path_ + ": more than " + std::to_string(height_) + " rows");
  line_[0] = 0;  // filter type None
  std::memcpy(line_.data() + 1, pixels, size_t(width_) * 3);
  deflate_into_chunks(line_.data(), line_.size(), Z_NO_FLUSH);
  ++rows_;
}

void PngStream::close() {
  if (rows_ != height_) throw Error(path_ + ": " + std::to_string(rows_) + " of " + std::to_string(height_) + " rows written");
  deflate_into_chunks(nullptr, 0, Z_FINISH);
  if (!idat_.empty()) chunk("IDAT", idat_.data(), idat_.size());
  idat_.clear();
  chunk("IEND", nullptr, 0);
  deflateEnd(&z_);
  z_open_ = false;
  out_.close();
  if (!out_) throw Error(path_ + ": write failed (disk full?)");
}

}  // namespace hf::lidar
