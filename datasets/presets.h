// Named synthetic scenes: geometry, camera trajectory, sensor-noise defaults and exposure, chosen by the names
// users type (`hashfusion generate --preset NAME`, `synthetic:NAME` inputs).
//
//   room         (default) a textured 4 x 4 x 3 m room with furniture (table, boxes, sphere, cylinder), camera on a
//                smooth orbit looking at the middle. The general-purpose sequence: every method should track it.
//   wall         one textured plane filling the view, camera moving in front of it. Depth constrains only the
//                normal translation and two rotations: ICP is degenerate in 3 directions (the two in-plane
//                translations and the rotation about the normal); photometric terms constrain them.
//   corridor     two long parallel walls plus floor and ceiling (infinite along x), camera moving along x. The
//                translation along the corridor is unconstrained by geometry (ICP degenerate in 1 direction).
//   textureless  the room geometry with one uniform colour: photometric tracking has no gradients except
//                shading edges; geometric tracking must carry the pose.
//   fast         the room, with exactly 15 degrees and 10 cm of camera motion between consecutive frames: tests
//                the convergence basin and coarse-to-fine pyramids.
//   holes        the room with 30% of the depth missing in blobs (on top of the usual sensor dropouts).
//   exposure     the room with a global colour gain changing between frames (0.6 .. 1.4): brightness constancy
//                is violated, as with auto-exposure.
//   loop         the room seen by a camera looking outwards from near its middle, one lap every 240 frames and
//                back to the start pose: tracking drifts over the lap, and the first walls come back into view
//                (loop closure).
//   kidnap       the room's orbit until frame 75, then the camera jumps back to frame 0's viewpoint (~0.7 m and
//                30 degrees away) and goes on: tracking cannot follow; relocalisation must find the mapped view.
//   unregistered the room's orbit with the colour camera 2.5 cm beside the depth camera and its focal length 10 %
//                shorter (a Kinect's 525 against 585 px), its image not registered to depth (7-Scenes): the
//                photometric rows pull against the geometric ones, which the pipeline must notice from the data.
//   sphere       a single textured sphere (radius 0.5 m at the origin) seen from a ring around it: fusion tests
//                compare the reconstruction with the analytic surface (see sphere_centre/radius below).
//
// Scenes are fixed per preset (the seed changes only the sensor noise and the exposure jitter); trajectories are
// analytic functions of the frame index, so any frame can be rendered on its own. World frame: z up, metres.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "core/se3.h"
#include "datasets/renderer.h"
#include "datasets/scene.h"
#include "datasets/sensor_noise.h"

namespace hf::datasets {

struct Preset {
  std::string name;
  std::string description;  // one line: what the preset is for
  Scene scene;
  std::function<SE3(int frame)> T_world_camera;                // the trajectory, frames at 30 Hz
  std::function<double(std::uint64_t seed, int frame)> gain;  // colour gain per frame (1 except `exposure`)
  NoiseOptions noise;                                          // the preset's sensor-noise defaults
  Lighting lighting;
  // The colour camera, where it is not the depth camera: colour is rendered from T_world_camera * T_depth_colour
  // with the focal lengths scaled by colour_focal_scale (same size and principal point) and handed out on the depth
  // camera's pixel grid as it is, unregistered, as 7-Scenes ships its Kinect's colour. The identity and 1 (every
  // preset but `unregistered`): colour registered to depth.
  SE3 T_depth_colour;
  double colour_focal_scale = 1.0;
  bool colour_registered() const { return colour_focal_scale == 1.0 && T_depth_colour.translation().isZero(0.0) &&
                                          T_depth_colour.rotation().isIdentity(0.0); }
};

// Throws hf::Error "unknown synthetic preset 'X' (known: corridor, exposure, ...)".
Preset make_preset(const std::string& name);
std::vector<std::string> preset_names();  // sorted
std::string default_preset_name();        // "room"

// The `sphere` preset's analytic surface.
inline const Eigen::Vector3d kSphereCentre{0.0, 0.0, 0.0};
constexpr double kSphereRadius_m = 0.5;

// The camera pose at `eye` looking at `target` (camera z towards it, camera y pointing as far down, i.e. against
// `up`, as possible). Throws hf::Error when eye == target or the view direction is parallel to `up`.
SE3 look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target,
            const Eigen::Vector3d& up = Eigen::Vector3d::UnitZ());
// n poses evenly spaced on a horizontal ring at distance_m from `centre`, elevation_rad above its plane, all
// looking at the centre.
std::vector<SE3> ring_poses(const Eigen::Vector3d& centre, double distance_m, int n, double elevation_rad = 0.3);
// n poses spread evenly (Fibonacci lattice) over the upper hemisphere at distance_m, elevations 10..80 degrees,
// all looking at the centre.
std::vector<SE3> hemisphere_poses(const Eigen::Vector3d& centre, double distance_m, int n);

}  // namespace hf::datasets
