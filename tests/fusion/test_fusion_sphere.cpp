// End to end: integrate depth of the analytic sphere from known poses at 1 cm voxels, then mesh and raycast and
// compare with the true surface (issue 3's accuracy targets).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "datasets/presets.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "fusion/mesh.h"
#include "fusion/raycast.h"
#include "tests/common/analytic_depth.h"

namespace hf::fusion {
namespace {

constexpr double kVoxel = 0.01;

VolumeParams fusion_sphere_params_1cm() {
  VolumeParams p;
  p.voxel_m = kVoxel;
  p.capacity_blocks = 1 << 15;
  return p;
}

struct Errors {
  double rms = 0.0, max = 0.0;
  size_t n = 0;
};

Errors mesh_errors(const TriangleMesh& mesh, const Eigen::Vector3d& c, double r) {
  Errors e;
  double sq = 0.0;
  for (const auto& p : mesh.vertices) {
    const double d = std::abs((p.cast<double>() - c).norm() - r);
    sq += d * d;
    e.max = std::max(e.max, d);
  }
  e.n = mesh.vertices.size();
  e.rms = e.n ? std::sqrt(sq / double(e.n)) : 0.0;
  return e;
}

// The noise-free sphere fused from 30 poses (20 over the upper hemisphere, 10 on a ring below the equator: the
// whole sphere is seen), meshed, and raycast from a pose none of the frames used, against the exact surface.
struct SphereResult {
  Errors mesh;
  double depth_rms_m = 0.0;
  double normal_rms_deg = 0.0, normal_median_deg = 0.0;
  int hits = 0, normals = 0, truth_hits = 0;
};

SphereResult fuse_noise_free_sphere(const IntegrateParams& params) {
  const PinholeCamera camera = PinholeCamera::preset("ros").scaled(1);  // 320 x 240
  const Eigen::Vector3d c = datasets::kSphereCentre;
  const double r = datasets::kSphereRadius_m;
  std::vector<SE3> poses = datasets::hemisphere_poses(c, 1.3, 20);
  for (const SE3& T : datasets::ring_poses(c, 1.3, 10, -0.6)) poses.push_back(T);
  EXPECT_EQ(poses.size(), 30u);
  VoxelBlockGrid grid(fusion_sphere_params_1cm());
  for (const SE3& T : poses)
    integrate(grid, testing::render_sphere_depth(camera, T, c, r), ColorImage(), camera, T, params);

  SphereResult out;
  out.mesh = mesh_errors(extract_mesh(grid), c, r);
  const SE3 T = datasets::look_at({0.9, -0.8, 0.45}, c);
  const RaycastResult ray = raycast(grid, camera, T);
  const DepthImage truth = testing::render_sphere_depth(camera, T, c, r);
  double sq = 0.0, nsq = 0.0;
  std::vector<double> angles;
  for (int y = 0; y < camera.height; ++y)
    for (int x = 0; x < camera.width; ++x) {
      out.truth_hits += truth(x, y) > 0.0f;
      if (ray.depth(x, y) == 0.0f || truth(x, y) == 0.0f) continue;
      const double d = double(ray.depth(x, y)) - truth(x, y);
      sq += d * d;
      ++out.hits;
      const hf_float4 nc = ray.normals(x, y);
      if (nc.w == 0.0f) continue;
      const hf_float4 v = ray.vertices(x, y);
      const Eigen::Vector3d p = T * Eigen::Vector3d(v.x, v.y, v.z);
      const Eigen::Vector3d nw = T.rotation() * Eigen::Vector3d(nc.x, nc.y, nc.z);
      const double a = std::acos(std::clamp(nw.dot((p - c).normalized()), -1.0, 1.0)) * 180.0 / M_PI;
      nsq += a * a;
      angles.push_back(a);
    }
  out.normals = int(angles.size());
  out.depth_rms_m = out.hits ? std::sqrt(sq / out.hits) : 0.0;
  out.normal_rms_deg = angles.empty() ? 0.0 : std::sqrt(nsq / double(angles.size()));
  if (!angles.empty()) {
    std::nth_element(angles.begin(), angles.begin() + angles.size() / 2, angles.end());
    out.normal_median_deg = angles[angles.size() / 2];
  }
  return out;
}

TEST(FusionSphere, NoiseFreeDepthFromThirtyPosesIsAccurate) {
  // Point-to-plane distances: the setting for an object scanned from all around (see IntegrateParams).
  IntegrateParams params;
  params.point_to_plane = true;
  const SphereResult s = fuse_noise_free_sphere(params);
  ASSERT_GT(s.mesh.n, 10000u);
  EXPECT_LE(s.mesh.rms, 0.2 * kVoxel) << "max " << s.mesh.max / kVoxel << " voxel";
  EXPECT_LE(s.mesh.max, 1.0 * kVoxel) << "rms " << s.mesh.rms / kVoxel << " voxel";
  EXPECT_GT(s.hits, s.truth_hits * 95 / 100);
  ASSERT_GT(s.normals, s.hits * 9 / 10);
  EXPECT_LE(s.depth_rms_m, 0.3 * kVoxel);
  // Issue 3: 2 degrees RMS. Measured 1.70 (median 0.81) at 320 x 240, 0.54 (median 0.42) from 640 x 480 frames:
  // what remains is the 320 x 240 depth image's resolution (the point-to-plane factor's finite differences over
  // 3 mm pixels on a 0.5 m sphere and beside its silhouette, the nearest pixel's lateral offset), not the fusion.
  EXPECT_LE(s.normal_rms_deg, 2.0) << "median " << s.normal_median_deg;
}

// Why point-to-plane: the projective distance of a voxel at true distance s seen at incidence theta is
// s / cos theta, so each view writes the surface's neighbourhood with its own slope (1 at normal incidence, 5.8 at
// 80 degrees), and which views reach a voxel changes from voxel to voxel (a grazing view's band covers a voxel just
// outside the sphere, not the one just inside). The zero crossing of every view is right, but the trilinear
// interpolation between voxels of different slopes bends it: on this sphere the voxels half a voxel from the surface
// hold 2.6-2.8 times their true distance (measured), and the raycast normals, central differences of that field,
// are 3.8 degrees RMS off. Scaled to point-to-plane distances all views agree on the slope (voxels within 2 voxels
// hold their true distance to within 0.03-0.2 voxel), and the normals fall to 1.7 degrees. (Projective stays the
// default: see IntegrateParams for the room and the noisy sphere, where it measures better.)
TEST(FusionSphere, PointToPlaneDistancesRemoveTheNormalBias) {
  IntegrateParams projective;
  projective.point_to_plane = false;
  IntegrateParams point_to_plane;
  point_to_plane.point_to_plane = true;
  const SphereResult a = fuse_noise_free_sphere(projective);
  const SphereResult b = fuse_noise_free_sphere(point_to_plane);
  // Measured projective: 3.81 degrees RMS (median 2.66), depth 0.165 voxel RMS, mesh 0.076 voxel RMS (0.39 max).
  // Measured point-to-plane: 1.70 (median 0.81), 0.095 voxel, 0.048 voxel RMS (0.50 max). Bounds: ~15 % above
  // each (deterministic, noise-free input; the slack covers compilers' float differences), and the improvement
  // itself at least 2x in RMS and 3x in median.
  EXPECT_GT(a.normal_rms_deg, 3.3);
  EXPECT_LE(a.normal_rms_deg, 4.5);
  EXPECT_LE(b.normal_rms_deg, 2.0);
  EXPECT_LE(b.normal_median_deg, 1.0);
  EXPECT_LT(2.0 * b.normal_rms_deg, a.normal_rms_deg);
  EXPECT_LT(3.0 * b.normal_median_deg, a.normal_median_deg);
  EXPECT_LE(a.mesh.rms, 0.1 * kVoxel);
  EXPECT_LE(b.mesh.rms, 0.06 * kVoxel);
  EXPECT_LE(b.depth_rms_m, 0.12 * kVoxel);
  EXPECT_LT(b.depth_rms_m, a.depth_rms_m);
}

TEST(FusionSphere, KinectNoiseIsAveragedAway) {
  datasets::SyntheticOptions o;
  o.preset = "sphere";
  o.frames = 240;
  o.camera = PinholeCamera::preset("ros").scaled(1);
  o.noise_enabled = true;
  const datasets::SyntheticSequence seq(o);
  VoxelBlockGrid grid(fusion_sphere_params_1cm());
  std::vector<double> rms;
  // 30 frames spread over the full ring (every 8th frame), errors after 2, 6 and 30 of them. Only the region all
  // of those frames can see is compared, through the minimum-weight filter (the mesh of a part seen once is as
  // noisy as one frame).
  for (int k = 0; k < 30; ++k) {
    const datasets::SyntheticFrame f = seq.frame(8 * k);
    integrate(grid, f.depth, f.color, seq.camera(), f.T_world_camera);
    if (k == 1 || k == 5 || k == 29) {
      MeshOptions mo;
      const Errors e = mesh_errors(extract_mesh(grid, mo), datasets::kSphereCentre, datasets::kSphereRadius_m);
      rms.push_back(e.rms);
    }
  }
  EXPECT_LE(rms[2], 0.5 * kVoxel) << rms[0] / kVoxel << " " << rms[1] / kVoxel << " " << rms[2] / kVoxel;
  EXPECT_LT(rms[2], rms[0]);
  EXPECT_LT(rms[1], rms[0]);
}

}  // namespace
}  // namespace hf::fusion
