// Fuzzes the LAS reader: any bytes either read completely or raise hf::Error; what is read must re-encode and read
// back to the same number of points.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <sstream>
#include <string>

#include "core/error.h"
#include "io/las.h"
#include "io/las_limits.h"

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
  // Issue 35: the header bounds hold for everything read (io/las.h).
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(header.scale[k]) >= hf::kLasMinScale && std::abs(header.scale[k]) <= hf::kLasMaxScale &&
          std::abs(header.offset[k]) <= hf::kLasMaxOffset && std::abs(header.min[k]) <= hf::kLasMaxCoordinate &&
          std::abs(header.max[k]) <= hf::kLasMaxCoordinate))
      std::abort();
  for (const hf::LasPoint& p : all)
    if (!(std::abs(p.x) <= hf::kLasMaxCoordinate && std::abs(p.y) <= hf::kLasMaxCoordinate &&
          std::abs(p.z) <= hf::kLasMaxCoordinate))
      std::abort();
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
