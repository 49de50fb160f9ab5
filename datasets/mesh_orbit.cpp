#include "datasets/mesh_orbit.h"

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "datasets/mesh_renderer.h"

namespace hf::datasets {

void MeshOrbitOptions::validate() const {
  if (frames < 1) throw Error("mesh orbit: frames must be at least 1");
  if (!(distance_m > 0) || !std::isfinite(distance_m)) throw Error("mesh orbit: distance_m must be positive");
  if (!(std::abs(elevation_deg) + std::abs(elevation_swing_deg) < 89))
    throw Error("mesh orbit: elevation_deg +- elevation_swing_deg must lie in (-89, 89)");
  if (!std::isfinite(sweep_deg)) throw Error("mesh orbit: sweep_deg must be finite");
  if (!(up_world.norm() > 0) || !target_world.allFinite()) throw Error("mesh orbit: up_world must be non-zero, target_world finite");
  const Eigen::Vector3d up = up_world.normalized();
  if (!((start_world - start_world.dot(up) * up).norm() > 1e-9 * start_world.norm()))
    throw Error("mesh orbit: start_world must not be parallel to up_world");
  noise.validate();
}

SE3 mesh_orbit_pose(const MeshOrbitOptions& o, int i) {
  const Eigen::Vector3d up = o.up_world.normalized();
  const Eigen::Vector3d front = (o.start_world - o.start_world.dot(up) * up).normalized(), side = up.cross(front);
  const double azimuth = o.sweep_deg * std::numbers::pi / 180.0 * i / o.frames;
  const double elevation = (o.elevation_deg + o.elevation_swing_deg * std::sin(2 * azimuth)) * std::numbers::pi / 180.0;
  const Eigen::Vector3d centre =
      o.target_world + o.distance_m * (std::cos(elevation) * (std::cos(azimuth) * front + std::sin(azimuth) * side) + std::sin(elevation) * up);
  // Camera axes: z towards the target, x = z cross up (right), y = z cross x (down).
  Eigen::Matrix3d R;
  R.col(2) = (o.target_world - centre).normalized();
  R.col(0) = R.col(2).cross(up).normalized();
  R.col(1) = R.col(2).cross(R.col(0));
  return SE3(R, centre);
}

double mesh_orbit_timestamp_s(int i) { return std::round(1e6 * i / 30.0) / 1e6; }

SyntheticFrame mesh_orbit_frame(const TriangleMesh& mesh, const MeshOrbitOptions& o, int i) {
  o.validate();
  if (i < 0 || i >= o.frames) throw Error("mesh orbit: frame " + std::to_string(i) + " is not in 0.." + std::to_string(o.frames - 1));
  SyntheticFrame f;
  f.index = i;
  f.timestamp_s = mesh_orbit_timestamp_s(i);
  f.T_world_camera = mesh_orbit_pose(o, i);
  const RenderedView view = render_mesh(mesh, o.camera, f.T_world_camera);
  f.depth_clean = view.depth;
  f.depth = o.noise.depth_noise_enabled() ? apply_depth_noise(view.depth, view.incidence_rad, o.noise, o.seed, std::uint64_t(i)) : view.depth;
  f.color = finish_colour(view.color, 1.0, o.noise.colour_sigma, o.seed, std::uint64_t(i));
  return f;
}

}  // namespace hf::datasets
