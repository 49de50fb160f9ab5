// PLY (Stanford polygon format) for meshes and point clouds.
//
// Reading accepts ascii, binary_little_endian and binary_big_endian 1.0 files:
//   - element "vertex" with float/double (or any scalar type) x y z; optional nx ny nz; optional colour
//     red green blue (also r g b, diffuse_red ...). Integer colours are taken as 0..255 (16-bit types are scaled
//     by 255/65535), floating-point colours as 0..1; alpha is ignored.
//   - element "face" with a list property "vertex_indices" or "vertex_index" (any integer count/index types);
//     polygons with more than three corners are fan-triangulated (0,i,i+1).
//   - element "tristrips" with a list "vertex_indices": -1 restarts a strip; strip triangles alternate winding
//     (i,i+1,i+2 / i+1,i,i+2) and degenerate ones (a repeated index) are dropped.
//   - every other element and property, of any PLY scalar type (char uchar short ushort int uint float double
//     and the int8 uint8 int16 uint16 int32 uint32 float32 float64 aliases), and lists, is skipped.
// Failure modes: hf::Error when the file cannot be opened; hf::ParseError for anything malformed, reading
// "FILE:LINE: expected ..." for header lines and ASCII body lines, and "FILE: vertex 123: ..." (element name and
// 0-based index) for binary bodies. Element counts are checked against the bytes left before anything is
// allocated; indices outside the vertex range, negative indices and non-finite coordinates or normals are errors.
//
// Writing produces binary_little_endian by default (ascii or big endian on request). Floats are written
// bit-exactly: binary copies bits, ascii uses the shortest decimal that reads back to the same float.
// Files are written atomically (core/atomic_file.h); the value is validate()d first (hf::Error if inconsistent).
//
// Thread-safety: all functions are reentrant; no shared state.
#pragma once

#include <string>
#include <string_view>

#include "io/mesh.h"

namespace hf {

enum class PlyFormat { binary_little_endian, binary_big_endian, ascii };

struct PlyWriteOptions {
  PlyFormat format = PlyFormat::binary_little_endian;
  std::string comment = "written by hashfusion";  // one "comment" header line per text line; empty: none
};

// Reads vertices, per-vertex normals and colours when present, and triangles from "face" and "tristrips".
TriangleMesh read_ply_mesh(const std::string& path);
// Same, from the bytes of a whole file; `name_for_errors` takes the place of the path in messages.
TriangleMesh parse_ply_mesh(std::string_view bytes, const std::string& name_for_errors);

// Reads the vertex element as a point cloud; face-like elements are parsed (and so validated) but dropped.
PointCloud read_ply_point_cloud(const std::string& path);
PointCloud parse_ply_point_cloud(std::string_view bytes, const std::string& name_for_errors);

// Writes vertices (float x y z), normals (float nx ny nz) and colours (uchar red green blue) when present, and
// for a mesh an element "face" of "list uchar int vertex_indices".
void write_ply(const std::string& path, const TriangleMesh& mesh, const PlyWriteOptions& options = {});
void write_ply(const std::string& path, const PointCloud& cloud, const PlyWriteOptions& options = {});
// The bytes write_ply would write.
std::string format_ply(const TriangleMesh& mesh, const PlyWriteOptions& options = {});
std::string format_ply(const PointCloud& cloud, const PlyWriteOptions& options = {});

}  // namespace hf
