// Wavefront OBJ for triangle meshes (geometry only: no materials, no texture coordinates).
//
// Writing: "v x y z" (or "v x y z r g b" with colours as floats in [0, 1], the MeshLab/Open3D extension), "vn" per
// vertex when the mesh has normals, and 1-based "f a b c" (or "f a//a b//b c//c" with normals). Floats are written in
// the shortest form that reads back bit-exactly; colours read back exactly (round(c * 255)). Atomic
// (core/atomic_file.h); the mesh is validate()d first.
//
// Reading: "v x y z [w]" and "v x y z r g b [a]"; "vn"; "f" with corners "v", "v/t", "v//n" or "v/t/n", negative
// (relative) indices, polygons fan-triangulated (0, i, i+1). Everything else ("vt", "g", "o", "s", "usemtl",
// "mtllib", "l", "p", comments after '#') is ignored. OBJ normals belong to face corners; TriangleMesh keeps one per
// vertex: a vertex whose corners all name the same "vn" gets exactly that normal, one whose corners disagree gets their
// normalised mean, and one no corner gives a normal gets (0, 0, 0). When no face names a normal but there are as many
// "vn" as "v" lines, normals are taken by index. Colours must be on every "v" line or on none.
// Failure modes: hf::Error when the file cannot be opened; hf::ParseError "FILE:LINE: expected ..." for a malformed
// number, a non-finite coordinate, an index of 0 or outside the vertices/normals defined, a face with fewer than three
// corners.
//
// Thread-safety: all functions are reentrant; no shared state.
#pragma once

#include <string>
#include <string_view>

#include "io/mesh.h"

namespace hf {

struct ObjWriteOptions {
  std::string comment = "written by hashfusion";  // one "# " line per text line; empty: none
};

void write_obj(const std::string& path, const TriangleMesh& mesh, const ObjWriteOptions& options = {});
std::string format_obj(const TriangleMesh& mesh, const ObjWriteOptions& options = {});

TriangleMesh read_obj(const std::string& path);
TriangleMesh parse_obj(std::string_view text, const std::string& name_for_errors);

}  // namespace hf
