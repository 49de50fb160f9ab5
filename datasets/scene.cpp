#include "datasets/scene.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>

#include "core/error.h"

namespace hf::datasets {
namespace {

// Lattice hash: per-axis products combined by xor, then one multiply-xorshift mix (fixed integer arithmetic, so
// textures are identical on every platform; the per-axis products are shared by the 8 corners of a cell).
std::uint32_t mix(std::uint32_t h) {
  h ^= h >> 15;
  h *= 0x2C1B3C6Du;
  h ^= h >> 12;
  return h;
}

// floor() for |x| < 2^31 without a libm call (baseline x86-64 has no SSE4.1 round instruction).
std::int32_t fast_floor(double x) {
  const auto i = std::int32_t(x);
  return x < double(i) ? i - 1 : i;
}

double smooth(double t) { return t * t * (3.0 - 2.0 * t); }

// Trilinear value noise in [0, 1) with smoothstep weights (C1 continuous, so image gradients are well defined).
double value_noise(const Eigen::Vector3d& p, std::uint32_t seed) {
  const std::int32_t ix = fast_floor(p.x()), iy = fast_floor(p.y()), iz = fast_floor(p.z());
  const double ux = smooth(p.x() - ix), uy = smooth(p.y() - iy), uz = smooth(p.z() - iz);
  const std::uint32_t s = seed * 0x9E3779B9u;
  const std::uint32_t x0 = std::uint32_t(ix) * 73856093u, x1 = x0 + 73856093u;
  const std::uint32_t y0 = std::uint32_t(iy) * 19349663u, y1 = y0 + 19349663u;
  const std::uint32_t z0 = (std::uint32_t(iz) * 83492791u) ^ s, z1 = ((std::uint32_t(iz) + 1u) * 83492791u) ^ s;
  auto v = [](std::uint32_t h) { return double(mix(h) >> 8) * (1.0 / 16777216.0); };
  auto lerp = [](double a, double b, double t) { return a + (b - a) * t; };
  const double c00 = lerp(v(x0 ^ y0 ^ z0), v(x1 ^ y0 ^ z0), ux), c10 = lerp(v(x0 ^ y1 ^ z0), v(x1 ^ y1 ^ z0), ux);
  const double c01 = lerp(v(x0 ^ y0 ^ z1), v(x1 ^ y0 ^ z1), ux), c11 = lerp(v(x0 ^ y1 ^ z1), v(x1 ^ y1 ^ z1), ux);
  return lerp(lerp(c00, c10, uy), lerp(c01, c11, uy), uz);
}

bool finite_positive(double v) { return std::isfinite(v) && v > 0.0; }

// Smallest root of a t^2 + 2 b t + c = 0 greater than t_min (b is the half linear coefficient).
bool quadratic_first(double a, double b, double c, double t_min, double* t_out, double* t_far = nullptr) {
  const double disc = b * b - a * c;
  if (disc < 0.0 || a <= 0.0) return false;
  const double s = std::sqrt(disc);
  // Numerically stable pair of roots.
  const double q = -(b + std::copysign(s, b));
  double t0 = q / a, t1 = (q != 0.0) ? c / q : t0;
  if (t0 > t1) std::swap(t0, t1);
  if (t_far) *t_far = t1;
  if (t0 > t_min) {
    *t_out = t0;
    return true;
  }
  if (t1 > t_min) {
    *t_out = t1;
    return true;
  }
  return false;
}

// Intersections in the primitive's frame; n_local is the outward normal of the solid at the hit.
bool hit_plane(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double t_min, double* t, Eigen::Vector3d* n) {
  if (d.z() == 0.0) return false;
  const double tt = -o.z() / d.z();
  if (!(tt > t_min)) return false;
  *t = tt;
  *n = Eigen::Vector3d::UnitZ();
  return true;
}

bool hit_sphere(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double r, double t_min, double* t,
                Eigen::Vector3d* n) {
  double tt;
  if (!quadratic_first(d.squaredNorm(), o.dot(d), o.squaredNorm() - r * r, t_min, &tt)) return false;
  *t = tt;
  *n = (o + tt * d) / r;
  return true;
}

bool hit_box(const Eigen::Vector3d& o, const Eigen::Vector3d& d, const Eigen::Vector3d& h, double t_min, double* t,
             Eigen::Vector3d* n) {
  double t_near = -std::numeric_limits<double>::infinity(), t_far = std::numeric_limits<double>::infinity();
  int axis_near = -1, axis_far = -1;
  for (int k = 0; k < 3; ++k) {
    if (d[k] == 0.0) {
      if (std::abs(o[k]) > h[k]) return false;
      continue;
    }
    double t0 = (-h[k] - o[k]) / d[k], t1 = (h[k] - o[k]) / d[k];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_near) {
      t_near = t0;
      axis_near = k;
    }
    if (t1 < t_far) {
      t_far = t1;
      axis_far = k;
    }
  }
  if (t_near > t_far) return false;
  double tt;
  int axis;
  if (t_near > t_min) {
    tt = t_near;
    axis = axis_near;
  } else if (t_far > t_min) {
    tt = t_far;
    axis = axis_far;
  } else {
    return false;
  }
  if (axis < 0) return false;
  *t = tt;
  Eigen::Vector3d nn = Eigen::Vector3d::Zero();
  nn[axis] = (o[axis] + tt * d[axis]) > 0.0 ? 1.0 : -1.0;
  *n = nn;
  return true;
}

bool hit_cylinder(const Eigen::Vector3d& o, const Eigen::Vector3d& d, double r, double hh, double t_min, double* t,
                  Eigen::Vector3d* n) {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_n = Eigen::Vector3d::Zero();
  // Side: x^2 + y^2 = r^2 with |z| <= hh; both roots may be valid (entering and leaving).
  const double a = d.x() * d.x() + d.y() * d.y();
  if (a > 0.0) {
    const double b = o.x() * d.x() + o.y() * d.y();
    const double c = o.x() * o.x() + o.y() * o.y() - r * r;
    const double disc = b * b - a * c;
    if (disc >= 0.0) {
      const double s = std::sqrt(disc);
      for (double tt : {(-b - s) / a, (-b + s) / a}) {
        if (tt > t_min && tt < best && std::abs(o.z() + tt * d.z()) <= hh) {
          best = tt;
          const Eigen::Vector3d p = o + tt * d;
          best_n = Eigen::Vector3d(p.x(), p.y(), 0.0) / r;
        }
      }
    }
  }
  // Caps.
  if (d.z() != 0.0) {
    for (double zc : {-hh, hh}) {
      const double tt = (zc - o.z()) / d.z();
      if (tt > t_min && tt < best) {
        const Eigen::Vector3d p = o + tt * d;
        if (p.x() * p.x() + p.y() * p.y() <= r * r) {
          best = tt;
          best_n = Eigen::Vector3d(0.0, 0.0, zc > 0.0 ? 1.0 : -1.0);
        }
      }
    }
  }
  if (!std::isfinite(best)) return false;
  *t = best;
  *n = best_n;
  return true;
}

}  // namespace

Texture Texture::uniform(const Eigen::Vector3d& colour) {
  Texture t;
  t.pattern = Pattern::kUniform;
  t.colour_a = colour;
  t.colour_b = colour;
  t.noise_amount = 0.0;
  return t;
}

Eigen::Vector3d Texture::albedo(const Eigen::Vector3d& p) const {
  double pattern_value = 0.0;
  switch (pattern) {
    case Pattern::kUniform:
      break;
    case Pattern::kChecker: {
      const Eigen::Vector3d q = p / pattern_scale_m;
      const auto s = std::int64_t(fast_floor(q.x())) + fast_floor(q.y()) + fast_floor(q.z());
      pattern_value = (s & 1) ? 1.0 : 0.0;
      break;
    }
    case Pattern::kStripesZ:
      pattern_value = 0.5 + 0.5 * std::sin(2.0 * std::numbers::pi * p.z() / pattern_scale_m);
      break;
    case Pattern::kStripesXY:
      pattern_value = 0.5 + 0.5 * std::sin(2.0 * std::numbers::pi * (p.x() + p.y()) / (std::sqrt(2.0) * pattern_scale_m));
      break;
  }
  double t = pattern_value;
  if (noise_amount > 0.0) {
    const Eigen::Vector3d q = p / noise_scale_m;
    const double fbm = (2.0 / 3.0) * value_noise(q, noise_seed) + (1.0 / 3.0) * value_noise(2.03 * q, noise_seed + 7);
    t = (1.0 - noise_amount) * pattern_value + noise_amount * fbm;
  }
  t = std::clamp(t, 0.0, 1.0);
  return colour_a + t * (colour_b - colour_a);
}

Primitive Primitive::plane(const Eigen::Vector3d& point_world, const Eigen::Vector3d& normal_world,
                           const Texture& texture, const std::string& name) {
  Primitive p;
  p.kind = Kind::kPlane;
  const double len = normal_world.norm();
  if (!(len > 0.0) || !std::isfinite(len)) throw Error("plane '" + name + "': expected a non-zero normal");
  const Eigen::Vector3d n = normal_world / len;
  // Local z = n; any orthonormal completion.
  p.T_world_primitive = SE3(Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitZ(), n), point_world);
  p.texture = texture;
  p.name = name;
  return p;
}

Primitive Primitive::box(const SE3& T_world_box, const Eigen::Vector3d& half_extents_m, const Texture& texture,
                         const std::string& name) {
  Primitive p;
  p.kind = Kind::kBox;
  p.T_world_primitive = T_world_box;
  p.half_extents_m = half_extents_m;
  p.texture = texture;
  p.name = name;
  return p;
}

Primitive Primitive::sphere(const Eigen::Vector3d& centre_world, double radius_m, const Texture& texture,
                            const std::string& name) {
  Primitive p;
  p.kind = Kind::kSphere;
  p.T_world_primitive = SE3(Eigen::Quaterniond::Identity(), centre_world);
  p.radius_m = radius_m;
  p.texture = texture;
  p.name = name;
  return p;
}

Primitive Primitive::cylinder(const SE3& T_world_cylinder, double radius_m, double half_height_m,
                              const Texture& texture, const std::string& name) {
  Primitive p;
  p.kind = Kind::kCylinder;
  p.T_world_primitive = T_world_cylinder;
  p.radius_m = radius_m;
  p.half_height_m = half_height_m;
  p.texture = texture;
  p.name = name;
  return p;
}

double sdf_plane_local(const Eigen::Vector3d& p) { return p.z(); }

double sdf_box_local(const Eigen::Vector3d& p, const Eigen::Vector3d& h) {
  const Eigen::Vector3d q = p.cwiseAbs() - h;
  return q.cwiseMax(0.0).norm() + std::min(q.maxCoeff(), 0.0);
}

double sdf_sphere_local(const Eigen::Vector3d& p, double r) { return p.norm() - r; }

double sdf_cylinder_local(const Eigen::Vector3d& p, double r, double hh) {
  const double dx = std::hypot(p.x(), p.y()) - r, dz = std::abs(p.z()) - hh;
  return std::min(std::max(dx, dz), 0.0) + std::hypot(std::max(dx, 0.0), std::max(dz, 0.0));
}

int Scene::add(const Primitive& primitive) {
  const Primitive& p = primitive;
  const std::string what = "scene primitive '" + p.name + "'";
  if (!p.T_world_primitive.is_finite()) throw Error(what + ": expected a finite pose");
  switch (p.kind) {
    case Primitive::Kind::kPlane:
      break;
    case Primitive::Kind::kBox:
      if (!finite_positive(p.half_extents_m.x()) || !finite_positive(p.half_extents_m.y()) ||
          !finite_positive(p.half_extents_m.z()))
        throw Error(what + ": expected positive finite half extents");
      break;
    case Primitive::Kind::kSphere:
      if (!finite_positive(p.radius_m)) throw Error(what + ": expected a positive finite radius");
      break;
    case Primitive::Kind::kCylinder:
      if (!finite_positive(p.radius_m) || !finite_positive(p.half_height_m))
        throw Error(what + ": expected a positive finite radius and half height");
      break;
  }
  Cached c;
  const SE3 T_primitive_world = p.T_world_primitive.inverse();
  c.R_primitive_world = T_primitive_world.rotation();
  c.t_primitive_world = T_primitive_world.translation();
  c.bound_centre_world = p.T_world_primitive.translation();
  c.plane_normal_world = p.T_world_primitive.rotation().col(2);
  c.plane_offset_m = c.plane_normal_world.dot(p.T_world_primitive.translation());
  switch (p.kind) {
    case Primitive::Kind::kPlane:
      c.bound_radius_m = 0.0;
      break;
    case Primitive::Kind::kBox:
      c.bound_radius_m = p.half_extents_m.norm();
      break;
    case Primitive::Kind::kSphere:
      c.bound_radius_m = p.radius_m;
      break;
    case Primitive::Kind::kCylinder:
      c.bound_radius_m = std::hypot(p.radius_m, p.half_height_m);
      break;
  }
  primitives_.push_back(p);
  cached_.push_back(c);
  return int(primitives_.size()) - 1;
}

double Scene::sdf(const Eigen::Vector3d& p_world) const {
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const Primitive& prim = primitives_[i];
    const Eigen::Vector3d p = cached_[i].R_primitive_world * p_world + cached_[i].t_primitive_world;
    double d = 0.0;
    switch (prim.kind) {
      case Primitive::Kind::kPlane:
        d = sdf_plane_local(p);
        break;
      case Primitive::Kind::kBox:
        d = sdf_box_local(p, prim.half_extents_m);
        break;
      case Primitive::Kind::kSphere:
        d = sdf_sphere_local(p, prim.radius_m);
        break;
      case Primitive::Kind::kCylinder:
        d = sdf_cylinder_local(p, prim.radius_m, prim.half_height_m);
        break;
    }
    best = std::min(best, d);
  }
  return best;
}

int Scene::nearest_primitive(const Eigen::Vector3d& p_world) const {
  int best_i = -1;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < primitives_.size(); ++i) {
    Scene one;
    one.primitives_ = {primitives_[i]};
    one.cached_ = {cached_[i]};
    const double d = std::abs(one.sdf(p_world));
    if (d < best) {
      best = d;
      best_i = int(i);
    }
  }
  return best_i;
}

Scene::RayOrigin Scene::prepare(const Eigen::Vector3d& origin) const {
  RayOrigin r;
  r.origin_world = origin;
  const size_t n = primitives_.size();
  r.origin_local.resize(n);
  r.to_bound.resize(n);
  r.bound_c.resize(n);
  r.plane_distance.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const Cached& c = cached_[i];
    r.origin_local[i] = c.R_primitive_world * origin + c.t_primitive_world;
    r.to_bound[i] = origin - c.bound_centre_world;
    r.bound_c[i] = r.to_bound[i].squaredNorm() - c.bound_radius_m * c.bound_radius_m;
    r.plane_distance[i] = c.plane_offset_m - c.plane_normal_world.dot(origin);
  }
  return r;
}

std::optional<Hit> Scene::intersect(const Eigen::Vector3d& origin, const Eigen::Vector3d& direction, double t_min,
                                    double t_max) const {
  return intersect(prepare(origin), direction, t_min, t_max);
}

std::optional<Hit> Scene::intersect(const RayOrigin& ray_origin, const Eigen::Vector3d& direction, double t_min,
                                    double t_max) const {
  double best_t = t_max;
  int best_i = -1;
  Eigen::Vector3d best_n_local = Eigen::Vector3d::UnitZ();
  const double dd = direction.squaredNorm();
  if (!(dd > 0.0) || !std::isfinite(dd)) return std::nullopt;
  if (ray_origin.origin_local.size() != primitives_.size()) return std::nullopt;  // prepared for another scene
  for (size_t i = 0; i < primitives_.size(); ++i) {
    const Cached& c = cached_[i];
    const Primitive& prim = primitives_[i];
    if (prim.kind == Primitive::Kind::kPlane) {
      // n . (o + t d) = offset, in world coordinates: no transform needed.
      const double nd = c.plane_normal_world.dot(direction);
      if (nd == 0.0) continue;
      const double t = ray_origin.plane_distance[i] / nd;
      if (t > t_min && t < best_t) {
        best_t = t;
        best_i = int(i);
        best_n_local = Eigen::Vector3d::UnitZ();
      }
      continue;
    }
    {
      // Reject with the bounding sphere before transforming the ray: most rays miss most objects.
      const double b = ray_origin.to_bound[i].dot(direction);
      const double disc = b * b - dd * ray_origin.bound_c[i];
      if (disc < 0.0) continue;
      const double root = std::sqrt(disc);
      if ((-b + root) / dd <= t_min || (-b - root) / dd >= best_t) continue;
    }
    const Eigen::Vector3d& o = ray_origin.origin_local[i];
    const Eigen::Vector3d d = c.R_primitive_world * direction;
    double t = 0.0;
    Eigen::Vector3d n = Eigen::Vector3d::Zero();
    bool hit = false;
    switch (prim.kind) {
      case Primitive::Kind::kPlane:
        hit = hit_plane(o, d, t_min, &t, &n);
        break;
      case Primitive::Kind::kBox:
        hit = hit_box(o, d, prim.half_extents_m, t_min, &t, &n);
        break;
      case Primitive::Kind::kSphere:
        hit = hit_sphere(o, d, prim.radius_m, t_min, &t, &n);
        break;
      case Primitive::Kind::kCylinder:
        hit = hit_cylinder(o, d, prim.radius_m, prim.half_height_m, t_min, &t, &n);
        break;
    }
    if (hit && t < best_t) {
      best_t = t;
      best_i = int(i);
      best_n_local = n;
    }
  }
  if (best_i < 0) return std::nullopt;
  Hit h;
  h.t = best_t;
  h.point_world = ray_origin.origin_world + best_t * direction;
  h.primitive = best_i;
  Eigen::Vector3d n = cached_[best_i].R_primitive_world.transpose() * best_n_local;
  if (n.dot(direction) > 0.0) n = -n;  // seen from inside a solid or from behind a plane
  h.normal_world = n.normalized();
  return h;
}

Eigen::Vector3d Scene::albedo(const Hit& hit) const {
  if (hit.primitive < 0 || hit.primitive >= int(primitives_.size())) return Eigen::Vector3d::Zero();
  return primitives_[hit.primitive].texture.albedo(hit.point_world);
}

}  // namespace hf::datasets
