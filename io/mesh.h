// Surface and point-set value types shared by the mesh/point-cloud files (io/ply.h, io/obj.h, io/pcd.h) and by
// fusion (marching cubes writes a TriangleMesh).
//
// Plain data: units are those of the producer (metres for everything hashfusion writes), positions and normals are
// in one frame (the world frame for fused maps). Per-vertex attributes are either empty or have exactly one entry
// per vertex; validate() checks that before anything is written, and every reader returns validated values.
#pragma once

#include <Eigen/Core>
#include <cmath>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/image.h"

namespace hf {

namespace detail {

inline bool all_finite(const std::vector<Eigen::Vector3f>& v, size_t* bad) {
  for (size_t i = 0; i < v.size(); ++i)
    if (!std::isfinite(v[i].x()) || !std::isfinite(v[i].y()) || !std::isfinite(v[i].z())) {
      *bad = i;
      return false;
    }
  return true;
}

inline void check_attribute_sizes(const char* what, size_t n, const std::vector<Eigen::Vector3f>& normals,
                                  const std::vector<Rgb8>& colors, const char* point_word) {
  if (!normals.empty() && normals.size() != n)
    throw Error(std::string(what) + ": " + std::to_string(normals.size()) + " normals for " + std::to_string(n) +
                " " + point_word + " (expected none or one per " + point_word + ")");
  if (!colors.empty() && colors.size() != n)
    throw Error(std::string(what) + ": " + std::to_string(colors.size()) + " colours for " + std::to_string(n) +
                " " + point_word + " (expected none or one per " + point_word + ")");
}

}  // namespace detail

// An indexed triangle mesh. Triangles index `vertices` (0-based) and are wound counter-clockwise seen from the
// side the normals point to. `normals` (unit length by convention, not enforced) and `colors` are per vertex.
struct TriangleMesh {
  std::vector<Eigen::Vector3f> vertices;
  std::vector<Eigen::Vector3f> normals;  // empty or vertices.size()
  std::vector<Rgb8> colors;              // empty or vertices.size()
  std::vector<Eigen::Vector3i> triangles;

  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }

  // Throws hf::Error naming the problem: attribute arrays of the wrong size, a non-finite vertex or normal, a
  // triangle index outside [0, vertices.size()).
  void validate() const {
    detail::check_attribute_sizes("triangle mesh", vertices.size(), normals, colors, "vertices");
    size_t bad = 0;
    if (!detail::all_finite(vertices, &bad))
      throw Error("triangle mesh: vertex " + std::to_string(bad) + " has a non-finite coordinate");
    if (!detail::all_finite(normals, &bad))
      throw Error("triangle mesh: normal " + std::to_string(bad) + " has a non-finite component");
    const long long n = static_cast<long long>(vertices.size());
    for (size_t t = 0; t < triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        if (triangles[t][k] < 0 || triangles[t][k] >= n)
          throw Error("triangle mesh: triangle " + std::to_string(t) + " index " + std::to_string(triangles[t][k]) +
                      " is outside [0, " + std::to_string(n) + ")");
  }
};

// An unordered set of points with optional per-point normals and colours.
struct PointCloud {
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;  // empty or positions.size()
  std::vector<Rgb8> colors;              // empty or positions.size()

  size_t size() const { return positions.size(); }
  bool has_normals() const { return !normals.empty(); }
  bool has_colors() const { return !colors.empty(); }

  // Throws hf::Error on attribute arrays of the wrong size or a non-finite position or normal.
  void validate() const {
    detail::check_attribute_sizes("point cloud", positions.size(), normals, colors, "points");
    size_t bad = 0;
    if (!detail::all_finite(positions, &bad))
      throw Error("point cloud: point " + std::to_string(bad) + " has a non-finite coordinate");
    if (!detail::all_finite(normals, &bad))
      throw Error("point cloud: normal " + std::to_string(bad) + " has a non-finite component");
  }
};

}  // namespace hf
