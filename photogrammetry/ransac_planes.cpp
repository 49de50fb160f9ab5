#include "photogrammetry/ransac_planes.h"

#include <pcl/ModelCoefficients.h>
#include <pcl/console/print.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/sample_consensus/method_types.h>
#include <pcl/sample_consensus/model_types.h>
#include <pcl/segmentation/sac_segmentation.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace hf::photogrammetry {
namespace {

Eigen::Vector3d mean_of(const std::vector<Eigen::Vector3d>& points) {
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const auto& p : points) m += p;
  return points.empty() ? m : Eigen::Vector3d(m / double(points.size()));
}

}  // namespace

double robust_extent(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0.0;
  Eigen::Vector3d range;
  std::vector<double> v(points.size());
  for (int a = 0; a < 3; ++a) {
    for (size_t i = 0; i < points.size(); ++i) v[i] = points[i][a];
    const size_t lo = points.size() / 20, hi = points.size() - 1 - points.size() / 20;
    std::nth_element(v.begin(), v.begin() + long(lo), v.end());
    const double a_lo = v[lo];
    std::nth_element(v.begin(), v.begin() + long(hi), v.end());
    range[a] = v[hi] - a_lo;
  }
  return range.norm();
}

double mean_nearest_neighbour_distance(const std::vector<Eigen::Vector3d>& points, const std::vector<int>& indices) {
  if (indices.size() < 2) return 0.0;
  Eigen::Vector3d m = Eigen::Vector3d::Zero();
  for (const int i : indices) m += points[size_t(i)];
  m /= double(indices.size());
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(indices.size());
  for (const int i : indices) {
    const Eigen::Vector3f p = (points[size_t(i)] - m).cast<float>();
    cloud->push_back(pcl::PointXYZ(p.x(), p.y(), p.z()));
  }
  pcl::KdTreeFLANN<pcl::PointXYZ> tree;
  tree.setInputCloud(cloud);
  std::vector<int> nn(2);
  std::vector<float> d2(2);
  double sum = 0;
  for (size_t k = 0; k < cloud->size(); ++k) {
    // The first neighbour is the point itself (or a duplicate at distance 0, which is a true nearest neighbour).
    if (tree.nearestKSearch((*cloud)[k], 2, nn, d2) == 2) sum += std::sqrt(double(d2[1]));
  }
  return sum / double(cloud->size());
}

std::vector<PlaneSegment> segment_planes_ransac(const std::vector<Eigen::Vector3d>& points,
                                                const RansacPlaneOptions& options) {
  if (!(options.distance_threshold >= 0) || !std::isfinite(options.distance_threshold))
    throw Error("ransac planes: expected distance_threshold >= 0 (0: automatic)");
  if (options.max_iterations < 1 || options.max_planes < 0 || options.min_inliers < 3)
    throw Error("ransac planes: expected max_iterations >= 1, max_planes >= 0 and min_inliers >= 3");
  std::vector<PlaneSegment> segments;
  if (points.size() < options.min_inliers) return segments;
  double threshold = options.distance_threshold;
  if (threshold == 0) threshold = 0.005 * robust_extent(points);
  if (!(threshold > 0)) return segments;  // every point in one spot: no plane is defined

  const Eigen::Vector3d origin = mean_of(points);
  pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
  cloud->reserve(points.size());
  for (const auto& p : points) {
    const Eigen::Vector3f q = (p - origin).cast<float>();
    cloud->push_back(pcl::PointXYZ(q.x(), q.y(), q.z()));
  }
  std::vector<int> remaining(points.size());
  for (size_t i = 0; i < points.size(); ++i) remaining[i] = int(i);

  // PCL prints "sample points too similar or collinear" for every rejected sample of a cloud with duplicates.
  pcl::console::setVerbosityLevel(pcl::console::L_ERROR);
  pcl::SACSegmentation<pcl::PointXYZ> sac(/*random=*/false);
  sac.setModelType(pcl::SACMODEL_PLANE);
  sac.setMethodType(pcl::SAC_RANSAC);
  sac.setDistanceThreshold(threshold);
  sac.setMaxIterations(options.max_iterations);
  sac.setOptimizeCoefficients(true);
  sac.setInputCloud(cloud);
  while (int(segments.size()) < options.max_planes && remaining.size() >= options.min_inliers) {
    pcl::IndicesPtr indices(new pcl::Indices(remaining.begin(), remaining.end()));
    sac.setIndices(indices);
    pcl::PointIndices inliers;
    pcl::ModelCoefficients coefficients;
    sac.segment(inliers, coefficients);
    if (inliers.indices.size() < options.min_inliers || coefficients.values.size() != 4) break;
    Eigen::Vector4d plane(coefficients.values[0], coefficients.values[1], coefficients.values[2],
                          coefficients.values[3]);
    const double n = plane.head<3>().norm();
    if (!(n > 0) || !plane.allFinite()) break;
    plane /= n;
    plane[3] -= plane.head<3>().dot(origin);  // back from the centred frame: n . (X - o) + d = n . X + (d - n . o)
    PlaneSegment s;
    s.plane = plane;
    s.indices.assign(inliers.indices.begin(), inliers.indices.end());
    std::sort(s.indices.begin(), s.indices.end());
    s.mean_spacing = mean_nearest_neighbour_distance(points, s.indices);
    std::vector<int> rest;
    rest.reserve(remaining.size() - s.indices.size());
    std::set_difference(remaining.begin(), remaining.end(), s.indices.begin(), s.indices.end(),
                        std::back_inserter(rest));
    remaining.swap(rest);
    segments.push_back(std::move(s));
  }
  return segments;
}

}  // namespace hf::photogrammetry
