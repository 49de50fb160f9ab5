#include "bench/pcl_reference.h"

#include <pcl/filters/voxel_grid.h>
#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/ndt.h>

#include <chrono>
#include <stdexcept>

namespace hf::bench {
namespace {

using Cloud = pcl::PointCloud<pcl::PointXYZ>;

Cloud::Ptr downsample(const std::vector<Eigen::Vector3f>& points, float voxel_m) {
  Cloud::Ptr raw(new Cloud);
  raw->reserve(points.size());
  for (const Eigen::Vector3f& p : points) raw->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  Cloud::Ptr out(new Cloud);
  pcl::VoxelGrid<pcl::PointXYZ> grid;
  grid.setInputCloud(raw);
  grid.setLeafSize(voxel_m, voxel_m, voxel_m);
  grid.filter(*out);
  return out;
}

}  // namespace

PclAlignResult pcl_align(const std::string& method, const std::vector<Eigen::Vector3f>& source,
                         const std::vector<Eigen::Vector3f>& target, float voxel_m, float ndt_resolution_m) {
  const auto start = std::chrono::steady_clock::now();
  Cloud::Ptr src = downsample(source, voxel_m), tgt = downsample(target, voxel_m);
  PclAlignResult result;
  result.source_points = int(src->size());
  result.target_points = int(tgt->size());
  Cloud aligned;
  Eigen::Matrix4f T = Eigen::Matrix4f::Identity();
  if (method == "gicp") {
    pcl::GeneralizedIterativeClosestPoint<pcl::PointXYZ, pcl::PointXYZ> gicp;
    gicp.setInputSource(src);
    gicp.setInputTarget(tgt);
    gicp.setMaxCorrespondenceDistance(0.1);  // KinectFusion's 10 cm, as our icp
    gicp.setMaximumIterations(50);
    gicp.setTransformationEpsilon(1e-8);
    gicp.align(aligned);
    result.converged = gicp.hasConverged();
    T = gicp.getFinalTransformation();
  } else if (method == "ndt") {
    pcl::NormalDistributionsTransform<pcl::PointXYZ, pcl::PointXYZ> ndt;
    ndt.setInputSource(src);
    ndt.setInputTarget(tgt);
    ndt.setResolution(ndt_resolution_m);
    ndt.setStepSize(0.05);
    ndt.setTransformationEpsilon(1e-6);
    ndt.setMaximumIterations(50);
    ndt.align(aligned);
    result.converged = ndt.hasConverged();
    T = ndt.getFinalTransformation();
  } else {
    throw std::invalid_argument("pcl_align: unknown method '" + method + "' (gicp, ndt)");
  }
  result.T_target_source = T.cast<double>();
  result.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace hf::bench
