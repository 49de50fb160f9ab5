// Open3D's registration (0.16, Debian 12's libopen3d-dev) as optional reference rows of the benchmark, beside PCL's
// (bench/pcl_reference.h): peers, not hashfusion methods. Built only when find_package(Open3D) finds it
// (bench/harness/CMakeLists.txt); the project builds and tests without it. Open3D stays behind this header, which
// mentions Eigen and hashfusion's image types only.
//
// Methods, frame to frame (source = the current frame, target = the last good one):
//   "o3d-icp"          point-to-plane ICP (Chen and Medioni 1992; open3d::pipelines::registration::RegistrationICP
//                      with TransformationEstimationPointToPlane) on the voxel-downsampled clouds, target normals
//                      from a hybrid KD-tree search (radius 2 voxels, 30 neighbours) turned towards the camera;
//   "o3d-colored-icp"  Park et al. 2017 coloured ICP (RegistrationColoredICP, lambda_geometric 0.968, Open3D's
//                      default) on the same coloured clouds, normals on both;
//   "o3d-rgbd"         Open3D's hybrid RGB-D odometry (ComputeRGBDOdometry with RGBDOdometryJacobianFromHybridTerm:
//                      Steinbruecker et al. 2011 photometric + Park et al. 2017 depth terms, coarse-to-fine with
//                      Open3D's default 20/10/5 iterations per level, depth differences up to 3 cm, depth 0-4 m) on
//                      the full-resolution images.
// ICP settings: correspondences up to max_correspondence_m (0.1 m: KinectFusion's 10 cm as PCL's GICP peer and our
// icp), at most 30 iterations, relative fitness / RMSE change 1e-6 (Open3D's defaults). Clouds: every pixel_stride-th
// pixel back-projected with the camera, then Open3D's VoxelDownSample at voxel_m (the PCL peers' 0.04 m).
//
// Thread-safety: Open3D may use OpenMP inside; one call at a time per thread of the caller is safe.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"

namespace hf::bench {

// {"o3d-icp", "o3d-colored-icp", "o3d-rgbd"}.
std::vector<std::string> open3d_methods();

struct Open3dOptions {
  float voxel_m = 0.04f;
  int pixel_stride = 2;
  double max_correspondence_m = 0.1;
};

struct Open3dAlignResult {
  Eigen::Matrix4d T_target_source = Eigen::Matrix4d::Identity();  // maps source points into the target frame
  // ICP: a correspondence set was found (fitness > 0); RGB-D odometry: Open3D's success flag.
  bool converged = false;
  double fitness = 0.0;                       // ICP: inlier fraction of the source; odometry: 0
  int source_points = 0, target_points = 0;   // after downsampling (odometry: 0)
};

// Aligns `source` onto `target` (both RGB-D frames of `camera`, depth in metres, 0 = none) starting at `guess`
// (T_target_source). Throws std::invalid_argument for an unknown method or images that do not match the camera.
Open3dAlignResult open3d_align(const std::string& method, const DepthImage& source_depth,
                               const ColorImage& source_color, const DepthImage& target_depth,
                               const ColorImage& target_color, const PinholeCamera& camera,
                               const Eigen::Matrix4d& guess, const Open3dOptions& options);

}  // namespace hf::bench
