// Fuzzes the lidar tile files the merge reads (lidar/tiling.h): any bytes either read or raise hf::Error; a tile
// that reads must write back to the same bytes, and its header alone must read the same.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <string>

#include "core/error.h"
#include "lidar/tiling.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::string path = "/tmp/hf_fuzz_tile_" + std::to_string(::getpid()) + ".hflt";
  std::ofstream(path, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), std::streamsize(size));
  hf::lidar::TileResult t;
  try {
    t = hf::lidar::read_tile(path);
  } catch (const hf::Error&) {
    return 0;
  }
  const hf::lidar::TileResult h = hf::lidar::read_tile_header(path);
  if (h.core != t.core || h.buildings != t.buildings || h.cluster_cells.size() != t.cluster_cells.size()) std::abort();
  hf::lidar::write_tile(path, t);
  std::ifstream in(path, std::ios::binary);
  const std::string back{std::istreambuf_iterator<char>(in), {}};
  if (back != std::string(reinterpret_cast<const char*>(data), size)) std::abort();
  return 0;
}
