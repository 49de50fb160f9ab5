// Analytic scene: exact signed distances, ray intersections, and exact rendered depth of planes and spheres.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "core/camera.h"
#include "core/error.h"
#include "datasets/presets.h"
#include "datasets/renderer.h"
#include "datasets/scene.h"

namespace hf::datasets {
namespace {

using Eigen::Vector3d;

TEST(Scene, SignedDistancesOfPrimitives) {
  EXPECT_DOUBLE_EQ(sdf_sphere_local({2, 0, 0}, 0.5), 1.5);
  EXPECT_DOUBLE_EQ(sdf_sphere_local({0, 0, 0}, 0.5), -0.5);
  EXPECT_DOUBLE_EQ(sdf_box_local({2, 0, 0}, {1, 1, 1}), 1.0);
  EXPECT_DOUBLE_EQ(sdf_box_local({2, 2, 1}, {1, 1, 1}), std::sqrt(2.0));  // nearest point is an edge
  EXPECT_DOUBLE_EQ(sdf_box_local({0.5, 0, 0}, {1, 1, 1}), -0.5);
  EXPECT_DOUBLE_EQ(sdf_cylinder_local({3, 0, 0}, 1, 2), 2.0);
  EXPECT_DOUBLE_EQ(sdf_cylinder_local({0, 0, 3}, 1, 2), 1.0);
  EXPECT_DOUBLE_EQ(sdf_cylinder_local({4, 0, 6}, 1, 2), 5.0);  // rim: (3, 4) away
  EXPECT_DOUBLE_EQ(sdf_cylinder_local({0, 0, 0}, 1, 2), -1.0);

  Scene s;
  s.add(Primitive::plane({0, 0, 0}, {0, 0, 1}, Texture{}, "floor"));
  s.add(Primitive::sphere({0, 0, 2}, 0.5, Texture{}, "ball"));
  EXPECT_DOUBLE_EQ(s.sdf({0, 0, 1}), 0.5);                       // 1 above the floor, 0.5 below the ball
  EXPECT_DOUBLE_EQ(s.sdf({3, 0, 0.25}), 0.25);                   // floor nearer
  EXPECT_NEAR(s.sdf({0, 0, -0.5}), -0.5, 1e-15);                 // under the floor
  EXPECT_EQ(s.nearest_primitive({0, 0, 1.4}), 1);
  EXPECT_EQ(s.nearest_primitive({5, 0, 0.1}), 0);
}

TEST(Scene, RejectsBadPrimitives) {
  Scene s;
  EXPECT_THROW(s.add(Primitive::sphere({0, 0, 0}, -1.0, Texture{})), Error);
  EXPECT_THROW(s.add(Primitive::box(SE3(), {1, 0, 1}, Texture{})), Error);
  EXPECT_THROW(s.add(Primitive::cylinder(SE3(), 1, std::nan(""), Texture{})), Error);
  EXPECT_THROW(Primitive::plane({0, 0, 0}, {0, 0, 0}, Texture{}), Error);
}

// Every hit lies on the surface (sdf = 0) and is the first one: the scene is free along the ray before it.
TEST(Scene, RayHitsLieOnTheSurfaceOfEveryPrimitiveKind) {
  const Preset room = make_preset("room");
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int hits = 0;
  for (int k = 0; k < 4000; ++k) {
    const Vector3d origin(0.8 * u(rng), 0.8 * u(rng), 1.5 + 0.5 * u(rng));
    const Vector3d dir(u(rng), u(rng), u(rng));
    if (dir.norm() < 1e-3) continue;
    const auto hit = room.scene.intersect(origin, dir);
    ASSERT_TRUE(hit.has_value()) << "a closed room must stop every ray";
    ++hits;
    EXPECT_NEAR(room.scene.sdf(hit->point_world), 0.0, 1e-9);
    EXPECT_NEAR(hit->normal_world.norm(), 1.0, 1e-12);
    EXPECT_LE(hit->normal_world.dot(dir), 1e-12);
    // The normal is the sdf gradient (away from edges, where the finite difference is well defined).
    const double h = 1e-6;
    Vector3d g;
    for (int a = 0; a < 3; ++a) {
      Vector3d e = Vector3d::Zero();
      e[a] = h;
      g[a] = (room.scene.sdf(hit->point_world + e) - room.scene.sdf(hit->point_world - e)) / (2 * h);
    }
    if (std::abs(g.norm() - 1.0) < 1e-3) {
      EXPECT_GT(std::abs(g.normalized().dot(hit->normal_world)), 1.0 - 1e-4);
    }
    // Free space before the hit.
    for (double f : {0.25, 0.5, 0.9}) EXPECT_GT(room.scene.sdf(origin + f * hit->t * dir), 0.0);
  }
  EXPECT_GT(hits, 3900);
}

TEST(Scene, CylinderAndBoxHitsFromOutside) {
  Scene s;
  s.add(Primitive::cylinder(SE3(), 0.5, 1.0, Texture{}));
  auto side = s.intersect({2, 0, 0}, {-1, 0, 0});
  ASSERT_TRUE(side);
  EXPECT_DOUBLE_EQ(side->t, 1.5);
  EXPECT_TRUE(side->normal_world.isApprox(Vector3d(1, 0, 0)));
  auto cap = s.intersect({0.1, 0, 3}, {0, 0, -2});
  ASSERT_TRUE(cap);
  EXPECT_DOUBLE_EQ(cap->t, 1.0);
  EXPECT_TRUE(cap->normal_world.isApprox(Vector3d(0, 0, 1)));
  EXPECT_FALSE(s.intersect({2, 0, 0}, {1, 0, 0}));

  Scene b;
  b.add(Primitive::box(SE3(Eigen::Quaterniond(Eigen::AngleAxisd(std::numbers::pi / 4, Vector3d::UnitZ())), Vector3d::Zero()),
                       {1, 1, 1}, Texture{}));
  auto hb = b.intersect({5, 0, 0}, {-1, 0, 0});
  ASSERT_TRUE(hb);
  EXPECT_NEAR(hb->t, 5 - std::sqrt(2.0), 1e-12);  // the rotated box presents its edge
}

TEST(Scene, TexturesHaveGradientsAndUniformIsFlat) {
  Texture t;
  t.pattern = Texture::Pattern::kStripesZ;
  t.noise_amount = 0.5;
  const Vector3d a = t.albedo({0.1, 0.2, 0.3}), b = t.albedo({0.1, 0.2, 0.35});
  EXPECT_GT((a - b).norm(), 1e-3);
  const Texture flat = Texture::uniform({0.2, 0.4, 0.6});
  EXPECT_TRUE(flat.albedo({1, 2, 3}).isApprox(Vector3d(0.2, 0.4, 0.6)));
  EXPECT_TRUE(flat.albedo({-7, 2, 0.1}).isApprox(Vector3d(0.2, 0.4, 0.6)));
}

// Exact depth, noise off: a tilted plane and a sphere against closed-form ray intersections.
TEST(Renderer, PlaneDepthIsExact) {
  const Vector3d n = Vector3d(-1.0, 0.2, 0.1).normalized(), p0(2.0, 0.0, 0.0);
  Scene s;
  s.add(Primitive::plane(p0, n, Texture{}));
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  const SE3 T = look_at({0.1, -0.2, 0.3}, {2.0, 0.3, 0.1});
  const RenderedView v = render_view(s, cam, T);
  const Eigen::Matrix3d R = T.rotation();
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Vector3d d = R * Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0);
      const double z = n.dot(p0 - T.translation()) / n.dot(d);
      ASSERT_GT(z, 0.0);
      ASSERT_NEAR(v.depth(x, y), z, 1e-6 * z) << x << "," << y;
      const double theta = std::acos(std::abs(n.dot(d.normalized())));
      ASSERT_NEAR(v.incidence_rad(x, y), theta, 1e-5);
    }
}

TEST(Renderer, SphereDepthIsExact) {
  const Preset sphere = make_preset("sphere");
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  const SE3 T = ring_poses(kSphereCentre, 1.5, 5, 0.4)[2];
  const RenderedView v = render_view(sphere.scene, cam, T);
  const Eigen::Matrix3d R = T.rotation();
  const Vector3d o = T.translation() - kSphereCentre;
  int inside = 0;
  for (int y = 0; y < cam.height; ++y)
    for (int x = 0; x < cam.width; ++x) {
      const Vector3d d = R * Vector3d((x - cam.cx) / cam.fx, (y - cam.cy) / cam.fy, 1.0);
      // |o + t d| = r: t = (-b - sqrt(b^2 - a c)) / a.
      const double a = d.squaredNorm(), b = o.dot(d), c = o.squaredNorm() - kSphereRadius_m * kSphereRadius_m;
      const double disc = b * b - a * c;
      if (disc < -1e-9) {
        ASSERT_EQ(v.depth(x, y), 0.0f);
      } else if (disc > 1e-9) {
        ++inside;
        const double z = (-b - std::sqrt(disc)) / a;
        ASSERT_NEAR(v.depth(x, y), z, 1e-6 * z) << x << "," << y;
      }
    }
  EXPECT_GT(inside, cam.width * cam.height / 5);
}

}  // namespace
}  // namespace hf::datasets
