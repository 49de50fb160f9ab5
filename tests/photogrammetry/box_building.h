// A synthetic box building for the photogrammetry tests: analytic geometry and colour, rendered into shots by ray
// casting (a small renderer here: datasets/ renders depth-camera sequences of its own scenes, not textured
// facades), and a noisy point cloud sampled on its walls and the ground. Deterministic by seed.
//
// World: z up, metres. The building is the box [0, 10] x [0, 8] x [0, 6]; its front facade is the plane y = 0 (normal
// -y) with 2 x 3 windows (1.4 m wide, 1.2 m tall, dark); the right facade is x = 10 (normal +x); the ground is z = 0.
// Facade colours vary smoothly (so textures can be compared by PSNR) and windows have sharp edges (for snapping).
#pragma once

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>
#include <vector>

#include "core/image.h"
#include "photogrammetry/network.h"
#include "tests/photogrammetry/synthetic_shots.h"

namespace hf::photogrammetry::testing {

struct BoxBuilding {
  Eigen::Vector3d lo{0, 0, 0}, hi{10, 8, 6};

  // Window k (0..5) on the front facade: x in [x0, x0 + 1.4], z in [z0, z0 + 1.2], y = 0.
  static Eigen::Vector2d window_origin(int k) { return {1.5 + 2.8 * (k % 3), 1.0 + 2.6 * (k / 3)}; }
  static std::vector<Eigen::Vector3d> window_corners(int k) {
    const Eigen::Vector2d o = window_origin(k);
    return {{o.x(), 0, o.y()}, {o.x() + 1.4, 0, o.y()}, {o.x() + 1.4, 0, o.y() + 1.2}, {o.x(), 0, o.y() + 1.2}};
  }
  std::vector<Eigen::Vector3d> front_corners() const { return {{0, 0, 0}, {10, 0, 0}, {10, 0, 6}, {0, 0, 6}}; }
  std::vector<Eigen::Vector3d> right_corners() const { return {{10, 0, 0}, {10, 8, 0}, {10, 8, 6}, {10, 0, 6}}; }

  static Rgb8 rgb(double r, double g, double b) {
    auto c = [](double v) { return std::uint8_t(std::clamp(std::lround(v), 0L, 255L)); };
    return {c(r), c(g), c(b)};
  }
  // Surface colour at a point of the front facade (y = 0).
  static Rgb8 front_color(double x, double z) {
    for (int k = 0; k < 6; ++k) {
      const Eigen::Vector2d o = window_origin(k);
      if (x >= o.x() && x <= o.x() + 1.4 && z >= o.y() && z <= o.y() + 1.2) return rgb(40, 55, 80);
    }
    return rgb(190 + 30 * std::sin(1.3 * x), 130 + 25 * std::sin(0.9 * z + 0.5 * x), 90 + 20 * std::cos(1.1 * z));
  }
  static Rgb8 right_color(double y, double z) { return rgb(140 + 30 * std::sin(y), 150, 120 + 25 * std::cos(z)); }
  static Rgb8 ground_color(double x, double y) {
    return rgb(90 + 15 * std::sin(0.7 * x), 110 + 15 * std::cos(0.6 * y), 80);
  }
  static Rgb8 sky() { return rgb(170, 200, 235); }

  // Colour seen along the ray C + t d (t > 0).
  Rgb8 trace(const Eigen::Vector3d& C, const Eigen::Vector3d& d) const {
    double t_box = INFINITY;
    int axis = -1;
    // Slab test: the entry face of the box.
    double t0 = -INFINITY, t1 = INFINITY;
    int entry_axis = -1;
    bool miss = false;
    for (int a = 0; a < 3; ++a) {
      if (std::fabs(d[a]) < 1e-15) {
        if (C[a] < lo[a] || C[a] > hi[a]) miss = true;
        continue;
      }
      double ta = (lo[a] - C[a]) / d[a], tb = (hi[a] - C[a]) / d[a];
      if (ta > tb) std::swap(ta, tb);
      if (ta > t0) {
        t0 = ta;
        entry_axis = a;
      }
      t1 = std::min(t1, tb);
    }
    if (!miss && t0 <= t1 && t0 > 0) {
      t_box = t0;
      axis = entry_axis;
    }
    const double t_ground = d.z() < 0 ? -C.z() / d.z() : INFINITY;
    if (t_ground < t_box) {
      const Eigen::Vector3d X = C + t_ground * d;
      return ground_color(X.x(), X.y());
    }
    if (axis < 0) return sky();
    const Eigen::Vector3d X = C + t_box * d;
    if (axis == 1 && d.y() > 0) return front_color(X.x(), X.z());
    if (axis == 0 && d.x() < 0) return right_color(X.y(), X.z());
    return rgb(120, 120, 125);  // left, back walls and roof
  }

  // The shot's image; samples at pixel centres.
  ColorImage render(const Shot& shot) const {
    ColorImage image(shot.width, shot.height);
    for (int v = 0; v < shot.height; ++v)
      for (int u = 0; u < shot.width; ++u) image(u, v) = trace(shot.C_world, shot.ray_world({double(u), double(v)}));
    return image;
  }

  // Points on the front and right facades (spacing_m grid, jittered) and on the ground in front, displaced along
  // their surface normal by N(0, noise_m). Front points inside the windows are left out (glass gives SfM no
  // features), so the front segment has holes.
  Cloud cloud(double spacing_m, double noise_m, unsigned seed) const {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> jitter(-0.3 * spacing_m, 0.3 * spacing_m);
    std::normal_distribution<double> noise(0, noise_m);
    Cloud c;
    auto add = [&](const Eigen::Vector3d& p, Rgb8 colour) {
      c.positions.push_back(p);
      c.colors.push_back(colour);
    };
    for (double x = spacing_m / 2; x < 10; x += spacing_m)
      for (double z = spacing_m / 2; z < 6; z += spacing_m) {
        const double px = x + jitter(rng), pz = z + jitter(rng);
        if (front_color(px, pz) == rgb(40, 55, 80)) continue;
        add({px, noise(rng), pz}, front_color(px, pz));
      }
    for (double y = spacing_m / 2; y < 8; y += spacing_m)
      for (double z = spacing_m / 2; z < 6; z += spacing_m) {
        const double py = y + jitter(rng), pz = z + jitter(rng);
        add({10 + noise(rng), py, pz}, right_color(py, pz));
      }
    for (double x = -4; x < 16; x += 2 * spacing_m)
      for (double y = -10; y < -0.5; y += 2 * spacing_m) {
        const double px = x + jitter(rng), py = y + jitter(rng);
        add({px, py, noise(rng)}, ground_color(px, py));
      }
    return c;
  }

  // Four shots: three in front (left, centre, right) and one off the right corner seeing both facades.
  static std::vector<Shot> shots(int width = 480, int height = 360, double f = 420) {
    return {look_at("front_left.png", {1, -17, 2.5}, {5, 0, 3}, f, width, height),
            look_at("front.png", {5, -16, 3}, {5, 0, 3}, f, width, height),
            look_at("front_right.png", {10, -17, 2.5}, {5, 0, 3}, f, width, height),
            look_at("corner.png", {19, -11, 3}, {7, 3, 3}, f, width, height)};
  }

  std::vector<Eigen::Vector2d> project(const Shot& shot, const std::vector<Eigen::Vector3d>& points) const {
    std::vector<Eigen::Vector2d> out;
    for (const auto& p : points) out.push_back(*shot.project(p));
    return out;
  }
};

}  // namespace hf::photogrammetry::testing
