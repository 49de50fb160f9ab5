#include "bench/open3d_reference.h"

#include <open3d/camera/PinholeCameraIntrinsic.h>
#include <open3d/geometry/Image.h>
#include <open3d/geometry/KDTreeSearchParam.h>
#include <open3d/geometry/PointCloud.h>
#include <open3d/geometry/RGBDImage.h>
#include <open3d/pipelines/odometry/Odometry.h>
#include <open3d/pipelines/registration/ColoredICP.h>
#include <open3d/pipelines/registration/Registration.h>
#include <open3d/pipelines/registration/TransformationEstimation.h>

#include <cmath>
#include <cstring>
#include <stdexcept>

namespace hf::bench {
namespace {

namespace o3g = open3d::geometry;
namespace o3r = open3d::pipelines::registration;

void check_size(const DepthImage& depth, const ColorImage& color, const PinholeCamera& camera) {
  if (depth.width() != camera.width || depth.height() != camera.height || color.width() != depth.width() ||
      color.height() != depth.height()) {
    throw std::invalid_argument("open3d_align: depth " + std::to_string(depth.width()) + "x" +
                                std::to_string(depth.height()) + " and colour " + std::to_string(color.width()) +
                                "x" + std::to_string(color.height()) + " must both match the camera's " +
                                std::to_string(camera.width) + "x" + std::to_string(camera.height));
  }
}

// Every stride-th valid depth pixel back-projected with its colour, voxel-downsampled.
std::shared_ptr<o3g::PointCloud> cloud_of(const DepthImage& depth, const ColorImage& color,
                                          const PinholeCamera& camera, const Open3dOptions& o) {
  o3g::PointCloud raw;
  for (int y = 0; y < depth.height(); y += o.pixel_stride) {
    for (int x = 0; x < depth.width(); x += o.pixel_stride) {
      const float d = depth(x, y);
      if (!(d > 0.0f) || !std::isfinite(d)) continue;
      raw.points_.push_back(camera.backproject(x, y, d));
      const Rgb8 c = color(x, y);
      raw.colors_.emplace_back(c.r / 255.0, c.g / 255.0, c.b / 255.0);
    }
  }
  return raw.VoxelDownSample(o.voxel_m);
}

void estimate_normals(o3g::PointCloud& cloud, const Open3dOptions& o) {
  cloud.EstimateNormals(o3g::KDTreeSearchParamHybrid(2.0 * o.voxel_m, 30));
  cloud.OrientNormalsTowardsCameraLocation(Eigen::Vector3d::Zero());
}

std::shared_ptr<o3g::RGBDImage> rgbd_of(const DepthImage& depth, const ColorImage& color) {
  o3g::Image d, c;
  d.Prepare(depth.width(), depth.height(), 1, 4);
  std::memcpy(d.data_.data(), depth.data(), depth.size() * sizeof(float));
  c.Prepare(color.width(), color.height(), 3, 1);
  std::memcpy(c.data_.data(), color.data(), color.size() * sizeof(Rgb8));
  // Depth already in metres (scale 1); no truncation here: OdometryOption's depth range applies.
  return o3g::RGBDImage::CreateFromColorAndDepth(c, d, 1.0, 1e6, true);
}

}  // namespace

std::vector<std::string> open3d_methods() { return {"o3d-icp", "o3d-colored-icp", "o3d-rgbd"}; }

Open3dAlignResult open3d_align(const std::string& method, const DepthImage& source_depth,
                               const ColorImage& source_color, const DepthImage& target_depth,
                               const ColorImage& target_color, const PinholeCamera& camera,
                               const Eigen::Matrix4d& guess, const Open3dOptions& options) {
  static_assert(sizeof(Rgb8) == 3, "Rgb8 must be packed RGB for the copy into open3d::geometry::Image");
  check_size(source_depth, source_color, camera);
  check_size(target_depth, target_color, camera);
  Open3dAlignResult result;
  if (method == "o3d-icp" || method == "o3d-colored-icp") {
    const auto source = cloud_of(source_depth, source_color, camera, options);
    const auto target = cloud_of(target_depth, target_color, camera, options);
    result.source_points = int(source->points_.size());
    result.target_points = int(target->points_.size());
    estimate_normals(*target, options);
    const o3r::ICPConvergenceCriteria criteria;  // 1e-6, 1e-6, 30 iterations
    o3r::RegistrationResult r;
    if (method == "o3d-icp") {
      r = o3r::RegistrationICP(*source, *target, options.max_correspondence_m, guess,
                               o3r::TransformationEstimationPointToPlane(), criteria);
    } else {
      estimate_normals(*source, options);
      r = o3r::RegistrationColoredICP(*source, *target, options.max_correspondence_m, guess,
                                      o3r::TransformationEstimationForColoredICP(), criteria);
    }
    result.T_target_source = r.transformation_;
    result.fitness = r.fitness_;
    result.converged = r.fitness_ > 0.0;
  } else if (method == "o3d-rgbd") {
    const auto source = rgbd_of(source_depth, source_color), target = rgbd_of(target_depth, target_color);
    const open3d::camera::PinholeCameraIntrinsic intrinsic(camera.width, camera.height, camera.fx, camera.fy,
                                                           camera.cx, camera.cy);
    const auto [ok, T, information] = open3d::pipelines::odometry::ComputeRGBDOdometry(
        *source, *target, intrinsic, guess, open3d::pipelines::odometry::RGBDOdometryJacobianFromHybridTerm(),
        open3d::pipelines::odometry::OdometryOption());
    (void)information;
    result.T_target_source = T;
    result.converged = ok;
  } else {
    throw std::invalid_argument("open3d_align: unknown method '" + method + "' (o3d-icp, o3d-colored-icp, o3d-rgbd)");
  }
  return result;
}

}  // namespace hf::bench
