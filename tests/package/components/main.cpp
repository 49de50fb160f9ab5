// Moves a triangle by an SE3, writes it as PLY and reads it back, and parses a one-pose TUM trajectory, through the
// installed hashfusion core and io components. Exit 0 when the mesh read back is the moved one (PLY stores float32:
// equal to 1e-6 m) and the parsed pose is T.
//
// Include order is the test: this project's own "core/se3.h" comes first and its folder is on the include path,
// then hashfusion headers that reach hashfusion's core/se3.h only through their own includes
// (io/trajectory_io.h). Had the installed headers kept `#include "core/se3.h"`, they would get this project's
// file, hf::SE3 would be undeclared and this would not compile.
#include "core/se3.h"  // this project's own header of the same name

#include <hashfusion/io/ply.h>
#include <hashfusion/io/trajectory_io.h>

#include <hashfusion/core/se3.h>  // already included by trajectory_io.h; as a consumer would write it

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

int main() {
  const hf::SE3 T = hf::SE3::exp((hf::Vector6d() << 0.1, -0.2, 0.3, 1.0, 2.0, 3.0).finished());
  hf::TriangleMesh mesh;
  for (const Eigen::Vector3d p : {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(0, 1, 0)})
    mesh.vertices.push_back((T * p).cast<float>());
  mesh.triangles.push_back({0, 1, 2});
  const std::string path = (std::filesystem::temp_directory_path() / "hf_components_consumer.ply").string();
  hf::write_ply(path, mesh);
  const hf::TriangleMesh back = hf::read_ply_mesh(path);
  std::filesystem::remove(path);

  double worst_m = 0;
  for (size_t i = 0; i < mesh.vertices.size() && back.vertices.size() == mesh.vertices.size(); ++i)
    worst_m = std::max(worst_m, double((back.vertices[i] - mesh.vertices[i]).norm()));
  const hf::Trajectory poses = hf::parse_tum_trajectory(hf::format_tum_trajectory({{1.5, T}}), "consumer");
  const double pose_error = poses.size() == 1 ? (poses[0].T_world_camera.matrix() - T.matrix()).norm() : 1.0;
  std::printf("components consumer (%s beside hashfusion's): %zu vertices back, largest difference %g m; "
              "pose error %g\n",
              consumer::kLocalHeader, back.vertices.size(), worst_m, pose_error);
  return back.vertices.size() == 3 && back.triangles.size() == 1 && worst_m < 1e-6 && pose_error < 1e-9 ? 0 : 1;
}
