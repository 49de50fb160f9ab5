#include "core/normals.h"

#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "tests/core/synthetic.h"

namespace hf {
namespace {

using test::test_camera;

Eigen::Vector3d vec(const hf_float4& v) { return {v.x, v.y, v.z}; }

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

// Derived bound on the angle between the computed normal at (x, y) and the true normal n_true of a surface
// whose vertices are exact up to float rounding. Each float vertex is within ~2 FLT_EPSILON |v| of the true point
// (depth rounded once, then (x - cx) / fx * d: two more roundings), so a tangent t = A - B tilts out of the
// surface by at most 4 eps |v| / |t|. On a sphere of radius R the chord A - B is additionally tilted by
// |A + B - 2P| / (2R) (a chord is perpendicular to the radius through its midpoint, which is that far from P).
// With the two tangents at angle phi, the normal error is at most (e_x + e_y) / sin(phi). Factor 2 for safety.
double normal_error_bound(const VertexMap& vm, int x, int y, double sphere_radius_m) {
  const Eigen::Vector3d p = vec(vm(x, y));
  const Eigen::Vector3d l = vec(vm(x - 1, y)), r = vec(vm(x + 1, y)), u = vec(vm(x, y - 1)), d = vec(vm(x, y + 1));
  const Eigen::Vector3d tx = r - l, ty = d - u;
  const double eps = FLT_EPSILON;
  double ex = 4.0 * eps * p.norm() / tx.norm(), ey = 4.0 * eps * p.norm() / ty.norm();
  if (sphere_radius_m > 0.0) {
    ex += (l + r - 2.0 * p).norm() / (2.0 * sphere_radius_m);
    ey += (u + d - 2.0 * p).norm() / (2.0 * sphere_radius_m);
  }
  const double sin_phi = tx.normalized().cross(ty.normalized()).norm();
  return 2.0 * (ex + ey) / sin_phi;
}

TEST(VertexMap, MatchesCameraBackprojection) {
  const PinholeCamera cam = test_camera(2);
  const DepthImage depth = test::render_plane(cam, Eigen::Vector3d(0.2, -0.1, 1.0).normalized(), 1.7);
  const VertexMap vm = compute_vertex_map(depth, cam);
  ASSERT_EQ(vm.width(), cam.width);
  ASSERT_EQ(vm.height(), cam.height);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3d expected = cam.backproject(x, y, depth(x, y));
      ASSERT_EQ(vm(x, y).w, 1.0f);
      ASSERT_LT((vec(vm(x, y)) - expected).norm(), 4.0 * FLT_EPSILON * expected.norm()) << x << "," << y;
    }
  }
}

TEST(VertexMap, CameraSizeMismatchThrows) {
  const PinholeCamera cam = test_camera(1);
  EXPECT_THROW(compute_vertex_map(DepthImage(cam.width / 2, cam.height / 2, 1.0f), cam), Error);
}

TEST(NormalMap, TiltedPlaneEqualsAnalyticNormal) {
  const PinholeCamera cam = test_camera(1);  // 320x240, f = 262.5
  const Eigen::Vector3d n = Eigen::Vector3d(0.4, -0.3, 1.0).normalized();
  const VertexMap vm = compute_vertex_map(test::render_plane(cam, n, 1.5), cam);
  const NormalMap nm = compute_normal_map(vm);
  double max_err = 0.0, sum_sq = 0.0;
  long count = 0;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      ASSERT_EQ(nm(x, y).w, 1.0f) << "plane normal undefined at " << x << "," << y;
      const double err = angle_between(vec(nm(x, y)), -n);  // oriented towards the camera: -n
      if (x > 0 && y > 0 && x < cam.width - 1 && y < cam.height - 1) {
        ASSERT_LT(err, normal_error_bound(vm, x, y, 0.0)) << x << "," << y;
      } else {
        ASSERT_LT(err, 2e-4) << "one-sided border normal " << x << "," << y;  // half the span: twice the bound
      }
      EXPECT_NEAR(vec(nm(x, y)).norm(), 1.0, 1e-6);
      max_err = std::max(max_err, err);
      sum_sq += err * err;
      ++count;
    }
  }
  const double rms = std::sqrt(sum_sq / double(count));
  RecordProperty("max_angle_error_rad", std::to_string(max_err));
  RecordProperty("rms_angle_error_rad", std::to_string(rms));
  // The float rounding of depth limits the accuracy to ~ eps * f; on average it is well under 1e-5 rad.
  EXPECT_LT(rms, 1e-5);
}

TEST(NormalMap, SphereNormalsWithinDerivedTolerance) {
  const PinholeCamera cam = test_camera(1);
  const Eigen::Vector3d centre(0.1, -0.05, 1.2);
  const double radius = 0.4;
  const DepthImage depth = test::render_sphere(cam, centre, radius);
  const VertexMap vm = compute_vertex_map(depth, cam);
  const NormalMap nm = compute_normal_map(vm);
  long checked = 0, interior = 0;
  double max_err = 0.0;
  for (int y = 1; y < cam.height - 1; ++y) {
    for (int x = 1; x < cam.width - 1; ++x) {
      if (!hf_is_valid4(vm(x, y))) {
        ASSERT_EQ(nm(x, y).w, 0.0f);
        continue;
      }
      const bool all_neighbours = hf_is_valid4(vm(x - 1, y)) && hf_is_valid4(vm(x + 1, y)) &&
                                  hf_is_valid4(vm(x, y - 1)) && hf_is_valid4(vm(x, y + 1));
      if (!all_neighbours) continue;
      // Away from the silhouette (incidence below 60 degrees) the normal must exist.
      const Eigen::Vector3d p = vec(vm(x, y));
      const Eigen::Vector3d n_true = (p - centre).normalized();
      const bool grazing = std::abs(n_true.dot(p.normalized())) < 0.5;
      if (!grazing) {
        ++interior;
        ASSERT_EQ(nm(x, y).w, 1.0f) << x << "," << y;
      }
      if (!hf_is_valid4(nm(x, y))) continue;
      EXPECT_LT(vec(nm(x, y)).dot(p), 0.0) << "normal must face the camera at " << x << "," << y;
      const double err = angle_between(vec(nm(x, y)), n_true);
      ASSERT_LT(err, normal_error_bound(vm, x, y, radius)) << x << "," << y;
      max_err = std::max(max_err, err);
      ++checked;
    }
  }
  EXPECT_GT(interior, 10000);
  EXPECT_GE(checked, interior);
  RecordProperty("max_angle_error_rad", std::to_string(max_err));
}

// Foreground: a tilted rectangle, a 1-pixel-wide vertical strip and a single pixel in front of a tilted
// background plane. Every valid normal must be its own surface's normal (one-sided differences at the edges);
// the strip (no usable horizontal neighbour) and the isolated pixel (none at all) must be invalid.
TEST(NormalMap, DepthEdgesGiveInvalidOrCorrectNormals) {
  const PinholeCamera cam = test_camera(2);  // 160x120
  const Eigen::Vector3d n_bg = Eigen::Vector3d(-0.2, 0.1, 1.0).normalized();
  const Eigen::Vector3d n_fg = Eigen::Vector3d(0.3, 0.2, 1.0).normalized();
  const double dist_bg = 2.5, dist_fg = 1.0;
  DepthImage depth = test::render_plane(cam, n_bg, dist_bg);
  Image<int> is_fg(cam.width, cam.height, 0);
  auto paint = [&](int x, int y) {
    depth(x, y) = float(test::plane_depth(cam, n_fg, dist_fg, x, y));
    is_fg(x, y) = 1;
  };
  for (int y = 30; y < 90; ++y)
    for (int x = 40; x < 100; ++x) paint(x, y);
  for (int y = 20; y < 100; ++y) paint(120, y);
  paint(140, 60);
  const VertexMap vm = compute_vertex_map(depth, cam);
  const NormalMap nm = compute_normal_map(vm);
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const Eigen::Vector3d expected = is_fg(x, y) ? -n_fg : -n_bg;
      if (!hf_is_valid4(nm(x, y))) {
        EXPECT_EQ(nm(x, y).x, 0.0f);
        EXPECT_EQ(nm(x, y).y, 0.0f);
        EXPECT_EQ(nm(x, y).z, 0.0f);
        continue;
      }
      // Border and edge pixels use one-sided differences: half the span, so twice the central-difference bound.
      EXPECT_LT(angle_between(vec(nm(x, y)), expected), 4e-4) << x << "," << y << (is_fg(x, y) ? " fg" : " bg");
    }
  }
  for (int y = 20; y < 100; ++y) EXPECT_EQ(nm(120, y).w, 0.0f) << "strip pixel 120," << y;
  EXPECT_EQ(nm(140, 60).w, 0.0f);
  // The background right next to the strip and the isolated pixel keeps a (one-sided) normal.
  EXPECT_EQ(nm(119, 50).w, 1.0f);
  EXPECT_EQ(nm(121, 50).w, 1.0f);
  EXPECT_EQ(nm(139, 60).w, 1.0f);
  // The rectangle's edge pixels too.
  EXPECT_EQ(nm(40, 50).w, 1.0f);
  EXPECT_EQ(nm(99, 50).w, 1.0f);
  EXPECT_EQ(nm(70, 30).w, 1.0f);
}

TEST(NormalMap, HolesUseOneSidedDifferences) {
  const PinholeCamera cam = test_camera(2);
  const Eigen::Vector3d n = Eigen::Vector3d(0.1, 0.5, 1.0).normalized();
  DepthImage depth = test::render_plane(cam, n, 2.0);
  depth(50, 50) = 0.0f;  // single hole: its four neighbours fall back to one side
  for (int x = 10; x < 150; ++x) depth(x, 80) = std::numeric_limits<float>::quiet_NaN();  // a NaN row
  depth(30, 79) = 0.0f;
  const VertexMap vm = compute_vertex_map(depth, cam);
  EXPECT_EQ(vm(50, 50).w, 0.0f);
  EXPECT_EQ(vm(60, 80).w, 0.0f);
  EXPECT_EQ(vm(60, 80).x, 0.0f);
  const NormalMap nm = compute_normal_map(vm);
  for (const auto& [x, y] : {std::pair{49, 50}, {51, 50}, {50, 49}, {50, 51}, {60, 79}, {60, 81}}) {
    ASSERT_EQ(nm(x, y).w, 1.0f) << x << "," << y;
    EXPECT_LT(angle_between(vec(nm(x, y)), -n), 4e-4) << x << "," << y;
  }
  // (30, 78) lost its lower neighbour (30, 79) but keeps the upper one: still defined, one-sided.
  EXPECT_EQ(nm(30, 78).w, 1.0f);
  EXPECT_EQ(nm(50, 50).w, 0.0f);
}

TEST(NormalMap, NoUsableVerticalNeighbourIsInvalid) {
  const PinholeCamera cam = test_camera(3);  // 80x60
  DepthImage depth(cam.width, cam.height, 0.0f);
  for (int x = 0; x < cam.width; ++x) depth(x, 30) = 1.0f;  // a single valid row
  const NormalMap nm = compute_normal_map(compute_vertex_map(depth, cam));
  for (const hf_float4& n : nm.pixels()) EXPECT_EQ(n.w, 0.0f);
}

TEST(NormalMap, AllInvalidDepthGivesAllInvalidMaps) {
  const PinholeCamera cam = test_camera(3);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  for (float value : {0.0f, nan, inf, -inf, -1.0f}) {
    const VertexMap vm = compute_vertex_map(DepthImage(cam.width, cam.height, value), cam);
    const NormalMap nm = compute_normal_map(vm);
    for (size_t i = 0; i < vm.size(); ++i) {
      ASSERT_EQ(vm.data()[i].w, 0.0f);
      ASSERT_EQ(vm.data()[i].z, 0.0f);
      ASSERT_EQ(nm.data()[i].w, 0.0f);
      ASSERT_EQ(nm.data()[i].z, 0.0f);
    }
  }
}

TEST(NormalMap, EmptyAndTinyImages) {
  EXPECT_TRUE(compute_normal_map(VertexMap()).empty());
  PinholeCamera cam = test_camera(0);
  cam.width = 1;
  cam.height = 1;
  const NormalMap nm = compute_normal_map(compute_vertex_map(DepthImage(1, 1, 1.0f), cam));
  EXPECT_EQ(nm(0, 0).w, 0.0f);
}

TEST(NormalMap, BadParamsThrow) {
  NormalParams p;
  p.max_depth_jump_ratio = 0.0f;
  EXPECT_THROW(compute_normal_map(VertexMap(4, 4), p), Error);
  p.max_depth_jump_ratio = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(compute_normal_map(VertexMap(4, 4), p), Error);
}

}  // namespace
}  // namespace hf
