// An RGB-D sequence of a triangle mesh seen from an orbit: the camera circles `target_world` at `distance_m`,
// `elevation_deg` (+- elevation_swing_deg) above the plane normal to `up_world`, starting in `start_world` (the direction from the target
// to the first camera, e.g. a head's nose direction for an orbit around the face) and turning `sweep_deg` over
// the frames, always looking at the target with the image's y axis down the world's up. Each frame is rendered by
// render_mesh and passed through the sensor model (sensor_noise.h; NoiseOptions::none() for exact depth), seeded
// by (seed, frame), so frame i depends only on (mesh, options, i). Units: metres; the mesh is in the world frame.
#pragma once

#include <Eigen/Core>
#include <cstdint>

#include "core/camera.h"
#include "datasets/sensor_noise.h"
#include "datasets/synthetic_sequence.h"
#include "io/mesh.h"

namespace hf::datasets {

struct MeshOrbitOptions {
  int frames = 36;
  Eigen::Vector3d target_world = Eigen::Vector3d::Zero();
  Eigen::Vector3d up_world = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d start_world = Eigen::Vector3d::UnitY();  // need not be normal to up_world; only its direction counts
  double distance_m = 0.5;     // inside the sensor's 0.4 .. 4.5 m range
  double elevation_deg = 10.0;
  // The elevation swings by this much, twice per turn (elevation_deg + swing sin(2 azimuth)), so the orbit sees
  // the top and the underside of an object too (a head's crown and chin), not only its sides at grazing angles.
  double elevation_swing_deg = 0.0;
  double sweep_deg = 360.0;    // frame i at azimuth sweep_deg * i / frames from the start
  PinholeCamera camera = PinholeCamera::preset("ros").scaled(1);
  NoiseOptions noise;
  std::uint64_t seed = 0;

  void validate() const;  // throws hf::Error naming the bad field
};

SE3 mesh_orbit_pose(const MeshOrbitOptions& options, int i);  // T_world_camera of frame i
double mesh_orbit_timestamp_s(int i);  // round(1e6 i / 30) / 1e6: 30 Hz, as SyntheticSequence
SyntheticFrame mesh_orbit_frame(const TriangleMesh& mesh_world, const MeshOrbitOptions& options, int i);

}  // namespace hf::datasets
