// Analytic scenes for synthetic RGB-D data: planes, boxes, spheres and capped cylinders with procedural solid
// textures. The scene knows its exact signed distance and its exact ray intersections, so tests can compare a
// reconstruction (or a rendered depth pixel) against the true surface.
//
// Frames: every primitive is placed by T_world_primitive; its shape is defined in its own frame:
//   plane    the z = 0 plane, solid below (z < 0), normal +z (a wall faces the free side);
//   box      |x| <= half_extents_m.x, |y| <= ..y, |z| <= ..z;
//   sphere   |p| <= radius_m;
//   cylinder x^2 + y^2 <= radius_m^2, |z| <= half_height_m (axis along local z, both ends capped).
// Distances are metres. The world has z up in the presets, but nothing here depends on that.
//
// Thread-safety: a Scene is immutable after construction as far as queries go; sdf(), intersect() and albedo()
// are const and safe to call from many threads at once.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <string>
#include <vector>

#include "core/se3.h"

namespace hf::datasets {

// A procedural solid texture evaluated at the world point, so a surface of any shape gets gradients in every
// direction along it. albedo = mix(colour_a, colour_b, t), t in [0, 1]:
//   t = clamp((1 - noise_amount) * pattern + noise_amount * fbm(p / noise_scale_m), 0, 1)
// where pattern is 0 for kUniform, a 3-D checker of cell pattern_scale_m for kChecker, smooth stripes of period
// pattern_scale_m along world z (kStripesZ) or along the world x + y diagonal (kStripesXY), and fbm is two-octave
// value noise in [0, 1] seeded by noise_seed. kUniform with noise_amount = 0 gives a flat colour_a.
struct Texture {
  enum class Pattern { kUniform, kChecker, kStripesZ, kStripesXY };
  Pattern pattern = Pattern::kUniform;
  Eigen::Vector3d colour_a{0.7, 0.7, 0.7};  // linear RGB in [0, 1]
  Eigen::Vector3d colour_b{0.3, 0.3, 0.3};
  double pattern_scale_m = 0.25;
  double noise_amount = 0.0;  // [0, 1]
  double noise_scale_m = 0.15;
  unsigned noise_seed = 1;

  static Texture uniform(const Eigen::Vector3d& colour);
  Eigen::Vector3d albedo(const Eigen::Vector3d& p_world) const;
};

struct Primitive {
  enum class Kind { kPlane, kBox, kSphere, kCylinder };
  Kind kind = Kind::kSphere;
  SE3 T_world_primitive;
  Eigen::Vector3d half_extents_m{0.5, 0.5, 0.5};  // box
  double radius_m = 0.5;                          // sphere, cylinder
  double half_height_m = 0.5;                     // cylinder
  Texture texture;
  std::string name;  // for messages and tests ("floor", "table top", ...)

  static Primitive plane(const Eigen::Vector3d& point_world, const Eigen::Vector3d& normal_world,
                         const Texture& texture, const std::string& name = "plane");
  static Primitive box(const SE3& T_world_box, const Eigen::Vector3d& half_extents_m, const Texture& texture,
                       const std::string& name = "box");
  static Primitive sphere(const Eigen::Vector3d& centre_world, double radius_m, const Texture& texture,
                          const std::string& name = "sphere");
  static Primitive cylinder(const SE3& T_world_cylinder, double radius_m, double half_height_m,
                            const Texture& texture, const std::string& name = "cylinder");
};

// A ray hit: origin + t * direction, with the direction as given (not necessarily unit length, so a camera ray
// with direction (x, y, 1) in the camera frame has t equal to the depth z of the hit).
struct Hit {
  double t = 0.0;
  Eigen::Vector3d point_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_world = Eigen::Vector3d::UnitZ();  // unit, facing the ray (dot(normal, direction) <= 0)
  int primitive = -1;                                       // index into Scene::primitives()
};

class Scene {
 public:
  Scene() = default;
  // Adds a primitive; throws hf::Error for non-finite or non-positive sizes or a zero plane normal.
  int add(const Primitive& primitive);

  const std::vector<Primitive>& primitives() const { return primitives_; }
  bool empty() const { return primitives_.empty(); }

  // Signed distance of the solid union of all primitives, metres: positive in free space, negative inside.
  // Exact in free space (the min of exact distances); inside overlapping solids it is a lower bound in magnitude.
  // An empty scene returns +infinity.
  double sdf(const Eigen::Vector3d& p_world) const;
  // The primitive whose surface is nearest to p_world (-1 for an empty scene).
  int nearest_primitive(const Eigen::Vector3d& p_world) const;

  // The first surface along origin + t * direction with t in (t_min, t_max); nullopt when none.
  std::optional<Hit> intersect(const Eigen::Vector3d& origin_world, const Eigen::Vector3d& direction_world,
                               double t_min = 1e-9, double t_max = 1e30) const;

  // The same for many rays from one origin (a camera centre): prepare() precomputes what depends only on the
  // origin, which the renderer reuses for every pixel. A RayOrigin is valid for the scene that prepared it, as long
  // as no primitive is added (else intersect returns nullopt).
  struct RayOrigin {
    Eigen::Vector3d origin_world = Eigen::Vector3d::Zero();
    std::vector<Eigen::Vector3d> origin_local;  // per primitive: the origin in its frame
    std::vector<Eigen::Vector3d> to_bound;      // origin - bounding-sphere centre
    std::vector<double> bound_c;                // |to_bound|^2 - bound radius^2
    std::vector<double> plane_distance;         // planes: offset - n . origin
  };
  RayOrigin prepare(const Eigen::Vector3d& origin_world) const;
  std::optional<Hit> intersect(const RayOrigin& origin, const Eigen::Vector3d& direction_world, double t_min = 1e-9,
                               double t_max = 1e30) const;

  // Texture colour of the hit's primitive at its point (linear RGB in [0, 1]).
  Eigen::Vector3d albedo(const Hit& hit) const;

 private:
  struct Cached {  // world -> local transform and a bounding sphere for fast ray rejection
    Eigen::Matrix3d R_primitive_world;
    Eigen::Vector3d t_primitive_world;
    Eigen::Vector3d bound_centre_world;
    double bound_radius_m = 0.0;  // 0 for unbounded (planes)
    Eigen::Vector3d plane_normal_world = Eigen::Vector3d::UnitZ();  // planes: n . p = offset
    double plane_offset_m = 0.0;
  };
  std::vector<Primitive> primitives_;
  std::vector<Cached> cached_;
};

// Signed distance of each shape in its own frame (exact).
double sdf_plane_local(const Eigen::Vector3d& p);
double sdf_box_local(const Eigen::Vector3d& p, const Eigen::Vector3d& half_extents_m);
double sdf_sphere_local(const Eigen::Vector3d& p, double radius_m);
double sdf_cylinder_local(const Eigen::Vector3d& p, double radius_m, double half_height_m);

}  // namespace hf::datasets
