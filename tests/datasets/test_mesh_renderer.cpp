// The mesh renderer against the analytic ray caster's geometry: a square of two triangles gives the exact
// ray-plane depth at every pixel centre inside it (fronto-parallel and tilted), the incidence angle of its normal,
// 0 outside, and the nearer of two overlapping squares; the mesh orbit's cameras look at the target from the
// stated distance and elevation.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "datasets/mesh_orbit.h"
#include "datasets/mesh_renderer.h"
#include "datasets/tum_writer.h"
#include "io/image_io.h"
#include "io/trajectory_io.h"

#include <unistd.h>

#include <filesystem>

namespace hf::datasets {
namespace {

// The square |x|, |y| <= half at depth z0 (camera frame = world frame), tilted about y by `tilt_rad`.
TriangleMesh square(double half, double z0, double tilt_rad) {
  TriangleMesh m;
  for (const auto& [x, y] : {std::pair{-1.0, -1.0}, {1.0, -1.0}, {1.0, 1.0}, {-1.0, 1.0}})
    m.vertices.push_back(Eigen::Vector3d(half * x * std::cos(tilt_rad), half * y, z0 + half * x * std::sin(tilt_rad)).cast<float>());
  m.triangles = {{0, 1, 2}, {0, 2, 3}};
  return m;
}

TEST(MeshRenderer, DepthIsTheRayPlaneIntersection) {
  const PinholeCamera camera = PinholeCamera::preset("ros").scaled(2);  // 160 x 120
  for (double tilt : {0.0, 0.5}) {
    SCOPED_TRACE("tilt " + std::to_string(tilt));
    const TriangleMesh m = square(0.2, 1.0, tilt);
    const RenderedView v = render_mesh(m, camera, SE3::identity());
    const Eigen::Vector3d n(-std::sin(tilt), 0, std::cos(tilt));  // the plane n . p = n . (0, 0, 1)
    int inside = 0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const Eigen::Vector3d d((x - camera.cx) / camera.fx, (y - camera.cy) / camera.fy, 1.0);
        const double t = n.z() / n.dot(d);
        const Eigen::Vector3d p = t * d;
        // In-plane coordinates of the hit; pixels within 1e-9 of an edge are left out (either answer is right).
        const double u = p.x() * std::cos(tilt) + (p.z() - 1.0) * std::sin(tilt), w = p.y();
        if (std::abs(std::abs(u) - 0.2) < 1e-9 || std::abs(std::abs(w) - 0.2) < 1e-9) continue;
        if (std::abs(u) < 0.2 && std::abs(w) < 0.2) {
          ++inside;
          EXPECT_NEAR(v.depth(x, y), t, 2e-7 * t);  // float storage
          EXPECT_NEAR(v.incidence_rad(x, y), std::acos(std::abs(n.dot(d)) / d.norm()), 1e-5);
        } else {
          EXPECT_EQ(v.depth(x, y), 0.0f);
        }
      }
    EXPECT_GT(inside, 100);
  }
}

TEST(MeshRenderer, NearerSurfaceWinsAndBehindTheCameraIsSkipped) {
  const PinholeCamera camera = PinholeCamera::preset("ros").scaled(2);
  TriangleMesh m = square(0.2, 1.0, 0.0);
  const TriangleMesh near = square(0.05, 0.5, 0.0), behind = square(0.3, -1.0, 0.0);
  for (const TriangleMesh* extra : {&near, &behind}) {
    const int base = int(m.vertices.size());
    m.vertices.insert(m.vertices.end(), extra->vertices.begin(), extra->vertices.end());
    for (const auto& t : extra->triangles) m.triangles.push_back(t + Eigen::Vector3i::Constant(base));
  }
  const RenderedView v = render_mesh(m, camera, SE3::identity());
  EXPECT_NEAR(v.depth(80, 60), 0.5, 1e-6);   // the centre sees the near square
  EXPECT_NEAR(v.depth(80 + 25, 60), 1.0, 1e-6);  // tan 0.19 off-axis: beyond the near square (0.1), inside the far (0.2)
  EXPECT_EQ(v.depth(2, 2), 0.0f);
}

TEST(MeshOrbit, CamerasLookAtTheTargetFromTheStatedPlace) {
  MeshOrbitOptions o;
  o.frames = 8;
  o.target_world = {1, 2, 3};
  o.distance_m = 0.6;
  o.elevation_deg = 20;
  for (int i = 0; i < o.frames; ++i) {
    const SE3 T = mesh_orbit_pose(o, i);
    const Eigen::Vector3d offset = T.translation() - o.target_world;
    EXPECT_NEAR(offset.norm(), 0.6, 1e-12);
    EXPECT_NEAR(std::asin(offset.z() / offset.norm()), 20 * std::numbers::pi / 180, 1e-12);
    const Eigen::Vector3d target_camera = T.inverse() * o.target_world;  // on the optical axis, ahead
    EXPECT_NEAR(target_camera.x(), 0, 1e-12);
    EXPECT_NEAR(target_camera.y(), 0, 1e-12);
    EXPECT_NEAR(target_camera.z(), 0.6, 1e-12);
    EXPECT_LT((T.rotation() * Eigen::Vector3d::UnitY()).z(), 0);  // image y points down the world's up
  }
  const Eigen::Vector3d first = mesh_orbit_pose(o, 0).translation() - o.target_world;
  EXPECT_GT(first.y(), 0);  // starts in start_world's direction (+y)
  o.start_world = Eigen::Vector3d::UnitZ();  // parallel to up
  EXPECT_THROW(o.validate(), hf::Error);
}

// A mesh orbit written as a TUM folder (what `generate --mesh` does): the poses read back as the ground truth, the
// depth PNGs hold the square at its distance (5000 units per metre: within 0.1 mm) and the time stamps are 30 Hz.
TEST(MeshOrbit, WritesATumFolder) {
  const TriangleMesh m = square(0.3, 0.0, 0.0);  // in the z = 0 plane, seen from +z
  MeshOrbitOptions o;
  o.frames = 3;
  o.camera = PinholeCamera::preset("ros").scaled(2);
  o.noise = NoiseOptions::none();
  o.up_world = Eigen::Vector3d::UnitY();
  o.start_world = Eigen::Vector3d::UnitZ();
  o.elevation_deg = 0;
  o.sweep_deg = 30;
  o.distance_m = 1.0;
  TumSequence seq;
  seq.frames = o.frames;
  seq.camera = o.camera;
  seq.list_name = seq.trajectory_name = "a test square";
  seq.timestamp_s = mesh_orbit_timestamp_s;
  seq.frame = [&](int i) { return mesh_orbit_frame(m, o, i); };
  const std::string dir = (std::filesystem::temp_directory_path() / ("hf_mesh_orbit_" + std::to_string(::getpid()))).string();
  std::filesystem::remove_all(dir);
  write_tum_folder(seq, dir);
  const Trajectory gt = read_tum_trajectory(dir + "/groundtruth.txt");
  ASSERT_EQ(gt.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    EXPECT_DOUBLE_EQ(gt[i].timestamp_s, mesh_orbit_timestamp_s(i));
    EXPECT_LT((gt[i].T_world_camera.translation() - mesh_orbit_pose(o, i).translation()).norm(), 1e-6);
  }
  const DepthImage d = load_depth(dir + "/depth/" + tum_stamp(0.0) + ".png");
  EXPECT_NEAR(d(80, 60), 1.0, 1e-4);  // frame 0 looks straight at the square from 1 m
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hf::datasets
