// PCD (Point Cloud Library format) for point clouds, through PCL; this header mentions hf types only, so including
// it does not pull PCL into the includer (link hf_io_pcl).
//
// Writing: binary PCD whose point type follows the attributes present -- pcl::PointXYZRGBNormal when the cloud has
// normals and colours, otherwise pcl::PointNormal, pcl::PointXYZRGB or pcl::PointXYZ -- so reading it back restores
// exactly the attributes written (floats bit-exact). An empty cloud is written as a valid file with POINTS 0.
// Atomic (core/atomic_file.h); the cloud is validate()d first.
//
// Reading: any PCD PCL reads (ascii, binary, binary_compressed); positions from x y z, normals from
// normal_x normal_y normal_z when present, colours from rgb or rgba when present. Points with a non-finite position
// (PCL's marker for "no measurement" in organized clouds) are dropped; a non-finite normal becomes (0, 0, 0).
// Failure modes: hf::Error when the file cannot be opened or written; hf::ParseError "FILE: expected ..." when PCL
// rejects the file or it has no x, y, z fields.
//
// Thread-safety: reentrant (PCL's reader and writer keep no shared state; PCL may print to its console).
#pragma once

#include <string>

#include "io/mesh.h"

namespace hf {

void write_pcd(const std::string& path, const PointCloud& cloud);
PointCloud read_pcd(const std::string& path);

}  // namespace hf
