// Fuzzes the OBJ reader: any bytes either parse into a valid mesh or raise hf::Error (file:line for malformed
// text); a parsed mesh must survive validate() and a write/read round trip unchanged in size.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.h"
#include "io/obj.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  hf::TriangleMesh mesh;
  try {
    mesh = hf::parse_obj(bytes, "fuzz.obj");
  } catch (const hf::Error&) {
    return 0;
  }
  mesh.validate();  // throws (and so aborts the fuzzer) if the reader let anything inconsistent through
  const hf::TriangleMesh again = hf::parse_obj(hf::format_obj(mesh), "roundtrip.obj");
  if (again.vertices.size() != mesh.vertices.size() || again.triangles.size() != mesh.triangles.size() ||
      again.normals.size() != mesh.normals.size() || again.colors.size() != mesh.colors.size())
    std::abort();
  return 0;
}
