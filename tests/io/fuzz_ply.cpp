// Fuzzes the PLY reader: any bytes either parse into a valid mesh or raise hf::Error; a parsed mesh must survive
// validate() and a binary write/read round trip unchanged in size.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.h"
#include "io/ply.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hf::TriangleMesh mesh;
  try {
    mesh = hf::parse_ply_mesh(bytes, "fuzz.ply");
  } catch (const hf::Error&) {
    return 0;
  }
  try {
    hf::parse_ply_point_cloud(bytes, "fuzz.ply");
  } catch (const hf::Error&) {
    std::abort();  // the point-cloud reader accepts whatever the mesh reader accepts
  }
  mesh.validate();  // throws (and so aborts the fuzzer) if the reader let anything inconsistent through
  const hf::TriangleMesh again = hf::parse_ply_mesh(hf::format_ply(mesh), "roundtrip.ply");
  if (again.vertices.size() != mesh.vertices.size() || again.triangles.size() != mesh.triangles.size() ||
      again.normals.size() != mesh.normals.size() || again.colors.size() != mesh.colors.size())
    std::abort();
  return 0;
}
