#include "slam/consistency.h"

#include <Eigen/Core>
#include <cmath>

#include "core/kernels/image_kernels.h"
#include "fusion/volume_sampler.h"

namespace hf::slam {
namespace consistency_detail {

// Every 4th pixel of `current` in x and y, moved by T (float): agree(p, z_cur) returns -1 (no overlap), 0 or 1.
template <class Agree>
Consistency sample(const VertexMap& current, const SE3& T, Agree agree) {
  const Eigen::Matrix3f R = T.rotation().cast<float>();
  const Eigen::Vector3f t = T.translation().cast<float>();
  Consistency c;
  constexpr int kStride = 4;
  for (int y = kStride / 2; y < current.height(); y += kStride) {
    for (int x = kStride / 2; x < current.width(); x += kStride) {
      const hf_float4& v = current(x, y);
      if (v.w == 0.0f) continue;
      ++c.sampled;
      const int a = agree(Eigen::Vector3f(R * Eigen::Vector3f(v.x, v.y, v.z) + t), v.z);
      if (a < 0) continue;
      ++c.overlap;
      c.consistent += a;
    }
  }
  return c;
}

}  // namespace consistency_detail

Consistency depth_consistency(const VertexMap& current, const DepthImage& reference_depth, const PinholeCamera& cam,
                              const SE3& T_ref_cur, double voxel_m) {
  return consistency_detail::sample(current, T_ref_cur, [&](const Eigen::Vector3f& p, float) {
    if (!(p.z() > 0.0f)) return -1;
    const Eigen::Vector2d px = cam.project(p.cast<double>());
    const int u = int(std::lround(px.x())), w = int(std::lround(px.y()));
    if (u < 0 || w < 0 || u >= cam.width || w >= cam.height) return -1;
    const float d_ref = reference_depth(u, w);
    if (!(d_ref > 0.0f)) return -1;
    return int(std::abs(d_ref - p.z()) <= 3.0f * hf_kinect_axial_sigma_m(p.z()) + float(voxel_m));
  });
}

Consistency volume_consistency(const VertexMap& current, const fusion::VoxelBlockGrid& grid, const SE3& T_world_cur) {
  const float inv_voxel = float(1.0 / grid.params().voxel_m), mu = float(grid.params().truncation_m());
  fusion::VolumeSampler sampler(grid, 0.0f, false);
  return consistency_detail::sample(current, T_world_cur, [&](const Eigen::Vector3f& p, float z_cur) {
    float s = 0.0f;
    if (!sampler.sdf(p * inv_voxel - Eigen::Vector3f::Constant(0.5f), &s)) return -1;
    return int(std::abs(s * mu) <= 3.0f * hf_kinect_axial_sigma_m(z_cur) + 1.0f / inv_voxel);
  });
}

}  // namespace hf::slam
