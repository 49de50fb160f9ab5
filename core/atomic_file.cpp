#include "core/atomic_file.h"

#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "core/error.h"

namespace hf {
namespace {

std::string temp_name(const std::string& path) {
  std::filesystem::path p(path);
  // Keep the extension last so writers that pick a format by extension (cv::imwrite) still work.
  std::string stem = p.stem().string();
  std::string tmp = stem + ".tmp" + std::to_string(::getpid()) + p.extension().string();
  return (p.parent_path() / tmp).string();
}

void commit(const std::string& tmp, const std::string& path) {
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw Error(path + ": cannot rename temporary output into place");
  }
}

}  // namespace

void write_file_atomically(const std::string& path, const std::function<void(std::ostream&)>& write, bool binary) {
  const std::string tmp = temp_name(path);
  try {
    std::ofstream out(tmp, binary ? std::ios::binary | std::ios::out : std::ios::out);
    if (!out) throw Error(path + ": cannot open for writing");
    write(out);
    out.flush();
    if (!out) throw Error(path + ": write failed (disk full?)");
    out.close();
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  commit(tmp, path);
}

void write_path_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const std::string tmp = temp_name(path);
  try {
    write(tmp);
    if (!std::filesystem::exists(tmp)) throw Error(path + ": writer produced no file");
  } catch (...) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw;
  }
  commit(tmp, path);
}

}  // namespace hf
