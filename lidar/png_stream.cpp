#include "lidar/png_stream.h"

#include <png.h>

#include <cerrno>
#include <csetjmp>
#include <cstdio>
#include <cstring>

#include "core/error.h"

namespace hf::lidar {

namespace {
constexpr size_t kIdatBytes = 64 * 1024;  // libpng writes one IDAT chunk per full compression buffer
constexpr size_t kErrorBytes = 200;
}  // namespace

static_assert(sizeof(Rgb8) == 3, "rows are handed to libpng as packed RGB");

struct PngStream::Libpng {
  png_structp png = nullptr;
  png_infop info = nullptr;
  std::FILE* file = nullptr;
  char error[kErrorBytes] = "";  // libpng's message of the failure that jumped back

  ~Libpng() {
    if (png) png_destroy_write_struct(&png, info ? &info : nullptr);
    if (file) std::fclose(file);
  }
};

namespace {

// libpng reports an error by calling this, which must not return: keep the message and jump back to the
// setjmp of the call in progress (guarded below).
[[noreturn]] void on_error(png_structp png, png_const_charp message) {
  auto* error = static_cast<char*>(png_get_error_ptr(png));
  std::snprintf(error, kErrorBytes, "%s", message ? message : "unknown libpng error");
  png_longjmp(png, 1);
}

void on_warning(png_structp, png_const_charp) {}  // the writes here raise none worth a line on stderr

// Runs `step` (libpng calls only) under libpng's setjmp protocol: false when libpng failed inside it. The frames a
// longjmp crosses (this one and step's) hold nothing with a destructor.
template <class Step>
bool guarded(png_structp png, const Step& step) {
  if (setjmp(png_jmpbuf(png))) return false;
  step();
  return true;
}

}  // namespace

PngStream::PngStream(const std::string& path, int width, int height)
    : path_(path), width_(width), height_(height), png_(std::make_unique<Libpng>()) {
  if (width <= 0 || height <= 0) throw Error(path + ": cannot write an empty PNG");
  Libpng& p = *png_;
  p.png = png_create_write_struct(PNG_LIBPNG_VER_STRING, p.error, on_error, on_warning);
  if (p.png) p.info = png_create_info_struct(p.png);
  if (!p.png || !p.info) throw Error(path + ": libpng cannot start (out of memory)");
  p.file = std::fopen(path.c_str(), "wb");
  if (!p.file) throw Error(path + ": cannot open for writing (" + std::strerror(errno) + ")");
  const bool ok = guarded(p.png, [&] {
    png_init_io(p.png, p.file);
    // Rasters wider or taller than libpng's default 10^6 limit are valid PNGs (up to 2^31 - 1): a country at 0.5 m.
    png_set_user_limits(p.png, 0x7fffffff, 0x7fffffff);
    png_set_IHDR(p.png, p.info, png_uint_32(width), png_uint_32(height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    // Filter None and level 6: what the hand-written writer did; class rasters are runs of a few colours, which
    // deflate finds without a filter, and adaptive filtering would cost a pass per row over 5 filters.
    png_set_filter(p.png, PNG_FILTER_TYPE_BASE, PNG_FILTER_NONE);
    png_set_compression_level(p.png, 6);
    png_set_compression_buffer_size(p.png, kIdatBytes);
    png_write_info(p.png, p.info);
  });
  if (!ok) throw Error(path + ": libpng: " + p.error);
}

PngStream::~PngStream() = default;

void PngStream::row(const Rgb8* pixels) {
  if (rows_ >= height_) throw Error(path_ + ": more than " + std::to_string(height_) + " rows");
  png_structp png = png_->png;
  // png_write_row takes a non-const row pointer but only reads it (no transformations are set).
  const auto bytes = reinterpret_cast<png_bytep>(const_cast<Rgb8*>(pixels));
  if (!guarded(png, [&] { png_write_row(png, bytes); }))
    throw Error(path_ + ": write failed (" + png_->error + "; disk full?)");
  ++rows_;
}

void PngStream::close() {
  if (rows_ != height_) throw Error(path_ + ": " + std::to_string(rows_) + " of " + std::to_string(height_) + " rows written");
  Libpng& p = *png_;
  if (!guarded(p.png, [&] { png_write_end(p.png, p.info); }))
    throw Error(path_ + ": write failed (" + p.error + "; disk full?)");
  std::FILE* file = p.file;
  p.file = nullptr;
  if (std::fflush(file) != 0 || std::ferror(file) != 0) {
    std::fclose(file);
    throw Error(path_ + ": write failed (disk full?)");
  }
  if (std::fclose(file) != 0) throw Error(path_ + ": write failed (disk full?)");
}

}  // namespace hf::lidar
