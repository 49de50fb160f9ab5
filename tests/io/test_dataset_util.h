// Helpers for the dataset-reader tests: a self-removing temporary folder and small synthetic RGB-D files.
#pragma once

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <string>

#include "core/camera.h"
#include "core/error.h"
#include "core/image.h"
#include "io/image_io.h"

namespace hf::test {

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& tag) {
    static int counter = 0;
    path = std::filesystem::temp_directory_path() /
           ("hf_test_" + tag + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::remove_all(path);
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string operator/(const std::string& name) const { return (path / name).string(); }
  std::string str() const { return path.string(); }
};

inline void write_text(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
}

// The message of the hf::Error that f throws, "" when it throws none.
inline std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const hf::Error& e) {
    return e.what();
  }
  return "";
}

inline bool contains(const std::string& haystack, const std::string& needle) {
  return haystack.find(needle) != std::string::npos;
}

// A tiny camera the synthetic frames match.
inline PinholeCamera tiny_camera(int width = 8, int height = 6) {
  PinholeCamera c;
  c.fx = c.fy = 10.0;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  c.width = width;
  c.height = height;
  return c;
}

// Depth image of constant `depth_m` and a colour image whose pixel (x, y) is (seed, x, y).
inline void write_frame_images(const std::string& depth_path, const std::string& color_path, int width, int height,
                               float depth_m, std::uint8_t seed, double scale = 5000.0) {
  std::filesystem::create_directories(std::filesystem::path(depth_path).parent_path());
  std::filesystem::create_directories(std::filesystem::path(color_path).parent_path());
  write_depth_png(depth_path, DepthImage(width, height, depth_m), scale);
  ColorImage c(width, height);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) c(x, y) = Rgb8{seed, std::uint8_t(x), std::uint8_t(y)};
  write_color_png(color_path, c);
}

inline void truncate_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  std::ofstream(path, std::ios::binary | std::ios::trunc) << bytes.substr(0, bytes.size() / 2);
}

}  // namespace hf::test
