// Triangle meshes of surfaces with known curvature for the mesh/ and head/ tests, generated in-process and
// deterministic by seed. All are wound counter-clockwise seen from outside (the normal side).
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>
#include <map>
#include <numbers>
#include <random>
#include <utility>

#include "io/mesh.h"

namespace hf::test {

// Icosahedron subdivided `levels` times (each triangle into four), vertices projected onto the sphere of `radius_m`
// centred at `centre`. levels 0..5: 12, 42, 162, 642, 2562, 10242 vertices.
inline TriangleMesh icosphere(double radius_m, int levels, const Eigen::Vector3d& centre = Eigen::Vector3d::Zero()) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<Eigen::Vector3i> f = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11},
                                    {1, 5, 9},  {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                    {3, 9, 4},  {3, 4, 2},  {3, 2, 6},   {3, 6, 8},  {3, 8, 9},
                                    {4, 9, 5},  {2, 4, 11}, {6, 2, 10},  {8, 6, 7},  {9, 8, 1}};
  for (auto& p : v) p.normalize();
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<Eigen::Vector3i> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f = std::move(g);
  }
  TriangleMesh m;
  for (const auto& p : v) m.vertices.push_back((centre + radius_m * p).cast<float>());
  m.triangles = f;
  return m;
}

// Height field z = height(x, y) over an n x n grid spanning [-half, half]^2 (split along alternating diagonals so
// the triangulation has no preferred direction). `jitter` moves interior grid points in x and y by up to that
// fraction of the spacing (seeded) before the height is evaluated, so the surface stays exact.
template <class Height>
TriangleMesh height_field(int n, double half, Height height, double jitter = 0.0, unsigned seed = 1) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-jitter, jitter);
  const double step = 2.0 * half / (n - 1);
  TriangleMesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      double x = -half + i * step, y = -half + j * step;
      if (i > 0 && j > 0 && i < n - 1 && j < n - 1) {
        x += u(rng) * step;
        y += u(rng) * step;
      }
      m.vertices.push_back(Eigen::Vector3d(x, y, height(x, y)).cast<float>());
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const int a = j * n + i, b = a + 1, c = a + n, d = c + 1;
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({a, b, d});
        m.triangles.push_back({a, d, c});
      } else {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({b, d, c});
      }
    }
  return m;
}

// Open cylinder of radius r around the z axis, `around` x `along` vertices over z in [-half_length, half_length].
inline TriangleMesh cylinder(double r, double half_length, int around, int along) {
  TriangleMesh m;
  for (int j = 0; j < along; ++j)
    for (int i = 0; i < around; ++i) {
      // Alternate rows are rotated by half a step so the triangles are close to equilateral.
      const double phi = 2.0 * std::numbers::pi * (i + 0.5 * (j % 2)) / around;
      const double z = -half_length + 2.0 * half_length * j / (along - 1);
      m.vertices.push_back(Eigen::Vector3d(r * std::cos(phi), r * std::sin(phi), z).cast<float>());
    }
  for (int j = 0; j + 1 < along; ++j)
    for (int i = 0; i < around; ++i) {
      const int a = j * around + i, b = j * around + (i + 1) % around;
      const int c = (j + 1) * around + i, d = (j + 1) * around + (i + 1) % around;
      if (j % 2 == 0) {
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({b, d, c});
      } else {
        m.triangles.push_back({a, d, c});
        m.triangles.push_back({a, b, d});
      }
    }
  return m;
}

// Torus around the z axis: tube radius r, centre-line radius R; vertex (i, j) at angles u = 2 pi i / nu around
// z and v = 2 pi j / nv around the tube (v = 0 outermost). Gaussian curvature cos v / (r (R + r cos v)).
inline TriangleMesh torus(double R, double r, int nu, int nv) {
  TriangleMesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const double u = 2.0 * std::numbers::pi * i / nu, v = 2.0 * std::numbers::pi * j / nv;
      m.vertices.push_back(
          Eigen::Vector3d((R + r * std::cos(v)) * std::cos(u), (R + r * std::cos(v)) * std::sin(u), r * std::sin(v))
              .cast<float>());
    }
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = i * nv + j, b = ((i + 1) % nu) * nv + j, c = i * nv + (j + 1) % nv,
                d = ((i + 1) % nu) * nv + (j + 1) % nv;
      m.triangles.push_back({a, b, d});
      m.triangles.push_back({a, d, c});
    }
  return m;
}

inline double torus_gaussian(double R, double r, int j, int nv) {
  const double v = 2.0 * std::numbers::pi * j / nv;
  return std::cos(v) / (r * (R + r * std::cos(v)));
}

}  // namespace hf::test
