#include "io/mesh_file.h"

#include <filesystem>

#include "core/error.h"
#include "io/obj.h"
#include "io/ply.h"

namespace hf {

TriangleMesh read_mesh_file(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".ply" || ext == ".PLY") return read_ply_mesh(path);
  if (ext == ".obj" || ext == ".OBJ") return read_obj(path);
  throw Error(path + ": expected a .ply or .obj mesh");
}

}  // namespace hf
