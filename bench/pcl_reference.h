// PCL's GeneralizedIterativeClosestPoint and NormalDistributionsTransform as reference rows of the registration
// benchmark (peers, not hashfusion methods). PCL stays behind this header (its templates take ~30 s to compile),
// which mentions Eigen only.
#pragma once

#include <Eigen/Core>
#include <string>
#include <vector>

namespace hf::bench {

struct PclAlignResult {
  Eigen::Matrix4d T_target_source = Eigen::Matrix4d::Identity();  // maps source points into the target frame
  bool converged = false;
  double ms = 0.0;  // downsampling + alignment
  int source_points = 0, target_points = 0;  // after the voxel grid
};

// method "gicp" or "ndt"; clouds in metres; both are voxel-grid downsampled to voxel_m first. NDT uses cells of
// ndt_resolution_m. The initial guess is the identity.
PclAlignResult pcl_align(const std::string& method, const std::vector<Eigen::Vector3f>& source,
                         const std::vector<Eigen::Vector3f>& target, float voxel_m, float ndt_resolution_m);

}  // namespace hf::bench
