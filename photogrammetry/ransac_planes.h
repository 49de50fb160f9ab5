// Planar segments of a point cloud by RANSAC (Kellner section 4.2 segments the cloud "using the RANSAC algorithm
// by Schnabel et al."; here PCL's SACSegmentation with the plane model, as the issue asks): the largest plane is
// found, its inliers removed, and the search repeats on the rest until a plane has fewer than min_inliers points or
// max_planes are found. Each plane is refitted to its inliers by least squares (PCL's optimised coefficients).
// PCL's sampler is seeded with a constant, so the segmentation is deterministic for a given cloud and options.
//
// This header mentions Eigen types only; PCL stays inside ransac_planes.cpp (slow to compile).
// Units are the cloud's. Points are centred on their mean before PCL sees them as floats, so a cloud far from the
// origin loses no precision. Failure modes: none thrown for any finite input (an empty or tiny cloud gives no
// segments); options outside their ranges throw hf::Error naming the option.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <vector>

namespace hf::photogrammetry {

struct RansacPlaneOptions {
  // Inlier distance to the plane, in the cloud's units; 0: 0.5 % of the cloud's robust extent (the diagonal of its
  // 5th-95th percentile box per axis), which is 4 cm on a 10 m building.
  double distance_threshold = 0.0;
  int max_iterations = 1000;   // RANSAC samples per plane
  size_t min_inliers = 50;     // a smaller best plane ends the search
  int max_planes = 20;
};

struct PlaneSegment {
  Eigen::Vector4d plane = Eigen::Vector4d::Zero();  // (n, d): n . X + d = 0 with |n| = 1
  std::vector<int> indices;                         // into the cloud given
  double mean_spacing = 0.0;  // q = (1/n) sum_i d_i, d_i the distance from point i to its nearest neighbour (eq. 2)
};

std::vector<PlaneSegment> segment_planes_ransac(const std::vector<Eigen::Vector3d>& points,
                                                const RansacPlaneOptions& options = {});

// The auto threshold above, exposed for reports.
double robust_extent(const std::vector<Eigen::Vector3d>& points);

// q of eq. 2 over points[indices] (k-d tree); 0 for fewer than two points.
double mean_nearest_neighbour_distance(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& indices);

}  // namespace hf::photogrammetry
