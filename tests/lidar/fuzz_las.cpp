// Fuzzes the LAS reader: any bytes either read completely or raise hf::Error; what is read must re-encode and read
// back to the same number of points.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/error.h"
#include "io/las.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string bytes(reinterpret_cast<const char*>(data), size);
  std::vector<hf::LasPoint> all, chunk;
  hf::LasHeader header;
  try {
    std::istringstream in(bytes);
    hf::LasReader reader(in, bytes.size(), "fuzz.las");
    while (reader.read_chunk(chunk, 5)) all.insert(all.end(), chunk.begin(), chunk.end());
    header = reader.header();
  } catch (const hf::Error&) {
    return 0;
  }
  if (all.size() != header.point_count) std::abort();
  header.vlrs.clear();
  header.record_length = 0;
  if (header.point_format >= 6) header.version_minor = 4;
  std::string again;
  try {
    again = hf::format_las(header, all, "again.las");
  } catch (const hf::Error&) {
    return 0;  // e.g. a huge scale whose positions do not fit 32 bits after rounding
  }
  std::istringstream in(again);
  hf::LasReader back(in, again.size(), "again.las");
  if (back.header().point_count != all.size()) std::abort();
  return 0;
}
