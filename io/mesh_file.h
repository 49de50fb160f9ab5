// A triangle mesh from a file, by extension: .ply (ASCII or binary, triangle strips included: io/ply.h) or .obj
// (io/obj.h). Throws hf::Error naming the file for another extension or a malformed file.
#pragma once

#include <string>

#include "io/mesh.h"

namespace hf {

TriangleMesh read_mesh_file(const std::string& path);

}  // namespace hf
