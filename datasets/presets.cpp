#include "datasets/presets.h"

#include <cmath>
#include <map>
#include <numbers>

#include "core/error.h"

namespace hf::datasets {
namespace {

using Eigen::Vector3d;
constexpr double kPi = std::numbers::pi;
constexpr double kFps = 30.0;

Texture textured(const Vector3d& a, const Vector3d& b, Texture::Pattern pattern, double scale_m, double noise,
                 unsigned seed, double noise_scale_m = 0.15) {
  Texture t;
  t.pattern = pattern;
  t.colour_a = a;
  t.colour_b = b;
  t.pattern_scale_m = scale_m;
  t.noise_amount = noise;
  t.noise_scale_m = noise_scale_m;
  t.noise_seed = seed;
  return t;
}

SE3 yaw_pose(double yaw_rad, const Vector3d& t) {
  return SE3(Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Vector3d::UnitZ())), t);
}

// The room: x, y in [-2, 2], z in [0, 3]; walls face inwards.
Scene room_scene(bool uniform) {
  using P = Texture::Pattern;
  auto tex = [&](const Texture& t) { return uniform ? Texture::uniform({0.62, 0.6, 0.58}) : t; };
  Scene s;
  s.add(Primitive::plane({0, 0, 0}, {0, 0, 1},
                         tex(textured({0.55, 0.42, 0.28}, {0.3, 0.22, 0.14}, P::kChecker, 0.5, 0.45, 11)), "floor"));
  s.add(Primitive::plane({0, 0, 3}, {0, 0, -1},
                         tex(textured({0.85, 0.85, 0.8}, {0.6, 0.62, 0.6}, P::kUniform, 0.5, 0.8, 12, 0.4)),
                         "ceiling"));
  s.add(Primitive::plane({2, 0, 0}, {-1, 0, 0},
                         tex(textured({0.35, 0.45, 0.7}, {0.75, 0.8, 0.9}, P::kStripesZ, 0.4, 0.5, 13)), "wall +x"));
  s.add(Primitive::plane({-2, 0, 0}, {1, 0, 0},
                         tex(textured({0.7, 0.55, 0.4}, {0.9, 0.85, 0.7}, P::kStripesXY, 0.6, 0.55, 14)), "wall -x"));
  s.add(Primitive::plane({0, 2, 0}, {0, -1, 0},
                         tex(textured({0.45, 0.65, 0.45}, {0.85, 0.9, 0.8}, P::kChecker, 0.7, 0.6, 15, 0.25)),
                         "wall +y"));
  s.add(Primitive::plane({0, -2, 0}, {0, 1, 0},
                         tex(textured({0.8, 0.75, 0.75}, {0.5, 0.35, 0.4}, P::kUniform, 0.5, 1.0, 16, 0.2)),
                         "wall -y"));
  // Table: top and four legs.
  const Vector3d table(0.5, 0.3, 0.0);
  s.add(Primitive::box(yaw_pose(0.0, table + Vector3d(0, 0, 0.75)), {0.6, 0.4, 0.025},
                       tex(textured({0.6, 0.35, 0.2}, {0.4, 0.2, 0.1}, P::kStripesXY, 0.08, 0.4, 21, 0.05)),
                       "table top"));
  for (int k = 0; k < 4; ++k) {
    const double lx = (k & 1) ? 0.55 : -0.55, ly = (k & 2) ? 0.35 : -0.35;
    s.add(Primitive::box(yaw_pose(0.0, table + Vector3d(lx, ly, 0.3625)), {0.03, 0.03, 0.3625},
                         tex(textured({0.2, 0.2, 0.2}, {0.35, 0.35, 0.35}, P::kUniform, 0.1, 1.0, 22 + k, 0.05)),
                         "table leg"));
  }
  s.add(Primitive::box(yaw_pose(0.35, {-1.3, 1.2, 0.25}), {0.25, 0.25, 0.25},
                       tex(textured({0.8, 0.3, 0.25}, {0.95, 0.8, 0.5}, P::kChecker, 0.125, 0.35, 31)), "crate"));
  s.add(Primitive::box(yaw_pose(-0.4, table + Vector3d(-0.2, -0.1, 0.875)), {0.12, 0.08, 0.1},
                       tex(textured({0.2, 0.5, 0.8}, {0.9, 0.9, 0.3}, P::kStripesZ, 0.05, 0.3, 32, 0.04)),
                       "box on table"));
  s.add(Primitive::box(yaw_pose(0.6, {1.35, -1.3, 0.45}), {0.3, 0.35, 0.45},
                       tex(textured({0.3, 0.3, 0.35}, {0.7, 0.7, 0.75}, P::kUniform, 0.1, 1.0, 33, 0.08)),
                       "cabinet"));
  s.add(Primitive::sphere({-0.8, -0.9, 0.35}, 0.35,
                          tex(textured({0.9, 0.6, 0.1}, {0.5, 0.15, 0.1}, P::kChecker, 0.15, 0.3, 41)), "ball"));
  s.add(Primitive::cylinder(yaw_pose(0.0, {-1.45, -0.1, 0.5}), 0.2, 0.5,
                            tex(textured({0.25, 0.55, 0.5}, {0.8, 0.9, 0.85}, P::kStripesZ, 0.2, 0.4, 51, 0.1)),
                            "pillar"));
  return s;
}

SE3 room_trajectory(int i) {
  const double t = i / kFps;
  const double phi = 0.35 + 0.22 * t;
  const double radius = 1.25 + 0.15 * std::sin(0.31 * t);
  const Vector3d eye(radius * std::cos(phi), radius * std::sin(phi), 1.45 + 0.12 * std::sin(0.53 * t));
  const Vector3d target(0.25 * std::cos(0.23 * t), 0.25 * std::sin(0.29 * t), 0.7);
  return look_at(eye, target);
}

Preset room_preset(const std::string& name, bool uniform) {
  Preset p;
  p.name = name;
  p.scene = room_scene(uniform);
  p.T_world_camera = room_trajectory;
  p.gain = [](std::uint64_t, int) { return 1.0; };
  return p;
}

Preset make_room() {
  Preset p = room_preset("room", false);
  p.description = "textured room with furniture on a smooth orbit: the general-purpose sequence";
  return p;
}

Preset make_textureless() {
  Preset p = room_preset("textureless", true);
  p.description = "room geometry in one uniform colour: no texture for photometric tracking";
  return p;
}

Preset make_holes() {
  Preset p = room_preset("holes", false);
  p.description = "room with 30% of the depth missing in blobs";
  p.noise.hole_fraction = 0.3;
  return p;
}

Preset make_exposure() {
  Preset p = room_preset("exposure", false);
  p.description = "room with a global colour gain changing between frames (0.6 .. 1.4), as with auto-exposure";
  p.gain = [](std::uint64_t seed, int i) {
    Rng rng(seed, std::uint64_t(i), 4);
    return 1.0 + 0.3 * std::sin(0.8 * i) + 0.2 * (rng.uniform() - 0.5);
  };
  return p;
}

Preset make_fast() {
  Preset p = room_preset("fast", false);
  p.description = "room with 15 degrees and 10 cm of motion between frames: tests the convergence basin";
  // On a circle of radius r the chord for 15 degrees is 2 r sin(7.5 deg) = 0.1 m; looking outwards along the
  // radius with a fixed pitch, consecutive orientations differ by exactly the 15 degree yaw step.
  const double step = 15.0 * kPi / 180.0;
  const double r = 0.05 / std::sin(step / 2);
  p.T_world_camera = [step, r](int i) {
    const double phi = 0.3 + step * i;
    const Vector3d dir(std::cos(phi), std::sin(phi), 0.0);
    const Vector3d eye = Vector3d(0.1, -0.1, 1.4) + r * dir;
    return look_at(eye, eye + dir - Vector3d(0, 0, std::tan(20.0 * kPi / 180.0)));
  };
  return p;
}

Preset make_wall() {
  Preset p;
  p.name = "wall";
  p.description = "one textured plane filling the view: ICP is unconstrained in 3 directions";
  p.scene.add(Primitive::plane(
      {2, 0, 0}, {-1, 0, 0},
      textured({0.3, 0.4, 0.65}, {0.9, 0.85, 0.7}, Texture::Pattern::kChecker, 0.3, 0.55, 61, 0.12), "wall"));
  p.T_world_camera = [](int i) {
    const double t = i / kFps;
    const Vector3d eye(0.4 + 0.15 * std::sin(0.7 * t), 0.3 * std::sin(0.45 * t), 1.5 + 0.2 * std::sin(0.6 * t));
    return look_at(eye, eye + Vector3d(1.0, 0.12 * std::sin(0.5 * t), 0.1 * std::sin(0.8 * t)));
  };
  p.gain = [](std::uint64_t, int) { return 1.0; };
  p.lighting.to_light_world = {-1.0, 0.3, 0.5};
  return p;
}

Preset make_corridor() {
  using P = Texture::Pattern;
  Preset p;
  p.name = "corridor";
  p.description = "long corridor walked along: the translation along it is unconstrained by geometry";
  p.scene.add(Primitive::plane({0, 1, 0}, {0, -1, 0},
                               textured({0.7, 0.6, 0.45}, {0.4, 0.3, 0.25}, P::kStripesZ, 0.5, 0.6, 71), "wall left"));
  p.scene.add(Primitive::plane({0, -1, 0}, {0, 1, 0},
                               textured({0.45, 0.55, 0.7}, {0.8, 0.85, 0.9}, P::kUniform, 0.5, 1.0, 72, 0.2),
                               "wall right"));
  p.scene.add(Primitive::plane({0, 0, 0}, {0, 0, 1},
                               textured({0.5, 0.5, 0.45}, {0.25, 0.25, 0.2}, P::kChecker, 0.4, 0.4, 73), "floor"));
  p.scene.add(Primitive::plane({0, 0, 2.5}, {0, 0, -1},
                               textured({0.85, 0.85, 0.85}, {0.65, 0.65, 0.7}, P::kUniform, 0.5, 1.0, 74, 0.3),
                               "ceiling"));
  p.T_world_camera = [](int i) {
    const double t = i / kFps;
    const Vector3d eye(0.9 * t, 0.25 * std::sin(0.4 * t), 1.3 + 0.08 * std::sin(0.7 * t));
    return look_at(eye, eye + Vector3d(1.0, 0.15 * std::sin(0.3 * t), -0.1 + 0.05 * std::sin(0.5 * t)));
  };
  p.gain = [](std::uint64_t, int) { return 1.0; };
  return p;
}

Preset make_sphere() {
  Preset p;
  p.name = "sphere";
  p.description = "one textured sphere (r = 0.5 m at the origin) seen from a ring: fusion against the true surface";
  p.scene.add(Primitive::sphere(
      kSphereCentre, kSphereRadius_m,
      textured({0.85, 0.5, 0.2}, {0.2, 0.4, 0.75}, Texture::Pattern::kChecker, 0.2, 0.4, 81, 0.08), "sphere"));
  p.T_world_camera = [](int i) {
    const double a = 2.0 * kPi * i / 240.0;
    const double elevation = 0.35 + 0.2 * std::sin(2.0 * kPi * i / 180.0);
    const double d = 1.6 + 0.1 * std::sin(2.0 * kPi * i / 150.0);
    const Vector3d eye =
        kSphereCentre + d * Vector3d(std::cos(elevation) * std::cos(a), std::cos(elevation) * std::sin(a),
                                     std::sin(elevation));
    return look_at(eye, kSphereCentre);
  };
  p.gain = [](std::uint64_t, int) { return 1.0; };
  return p;
}

// One lap looking outwards from near the room's middle, back to the start pose after kLoopFrames: each wall is
// seen once per lap, so tracking can only drift until the camera sees the first walls again (a loop to close).
constexpr int kLoopFrames = 240;  // 8 s a lap at 30 Hz: 1.5 degrees and ~1.3 cm per frame

Preset make_loop() {
  Preset p = room_preset("loop", false);
  p.description = "one outward-looking lap of the room every 240 frames, back to the start: drift to close";
  p.T_world_camera = [](int i) {
    const double phi = 0.3 + 2.0 * kPi * double(i) / kLoopFrames;
    const Vector3d dir(std::cos(phi), std::sin(phi), 0.0);
    const Vector3d eye = Vector3d(0.1, -0.1, 1.4) + 0.5 * dir;
    return look_at(eye, eye + dir - Vector3d(0, 0, std::tan(25.0 * kPi / 180.0)));
  };
  return p;
}

// The room's orbit until kKidnapFrame, then the camera is carried back to where frame 0 was (0.7 m and ~30 degrees
// away) and the orbit goes on from there: relocalisation must find the mapped view.
constexpr int kKidnapFrame = 75;

Preset make_kidnap() {
  Preset p = room_preset("kidnap", false);
  p.description = "the room's orbit, then at frame 75 a jump back to frame 0's viewpoint: relocalisation";
  p.T_world_camera = [](int i) { return room_trajectory(i < kKidnapFrame ? i : i - kKidnapFrame); };
  return p;
}

// The room's orbit seen by a depth camera and a colour camera that were never calibrated against each other: the
// colour is the colour camera's own image (a Kinect v1's colour sensor sits ~2.5 cm beside its depth sensor, with
// a focal length of ~525 px against the depth camera's ~585 px at 640x480).
Preset make_unregistered() {
  Preset p = room_preset("unregistered", false);
  p.description = "the room's orbit with colour from a camera 2.5 cm aside, focal 0.9x, unregistered to depth";
  p.T_depth_colour = SE3(Eigen::Matrix3d::Identity(), Vector3d(0.025, 0.0, 0.0));
  p.colour_focal_scale = 525.0 / 585.0;
  return p;
}

using Factory = Preset (*)();
const std::map<std::string, Factory>& factories() {
  static const std::map<std::string, Factory> table = {
      {"room", make_room},       {"wall", make_wall},   {"corridor", make_corridor},
      {"textureless", make_textureless}, {"fast", make_fast},   {"holes", make_holes},
      {"exposure", make_exposure},       {"sphere", make_sphere}, {"loop", make_loop},
      {"kidnap", make_kidnap},   {"unregistered", make_unregistered},
  };
  return table;
}

}  // namespace

Preset make_preset(const std::string& name) {
  const auto it = factories().find(name);
  if (it == factories().end()) {
    std::string known;
    for (const auto& n : preset_names()) known += (known.empty() ? "" : ", ") + n;
    throw Error("unknown synthetic preset '" + name + "' (known: " + known + ")");
  }
  return it->second();
}

std::vector<std::string> preset_names() {
  std::vector<std::string> names;
  for (const auto& [k, v] : factories()) names.push_back(k);
  return names;
}

std::string default_preset_name() { return "room"; }

SE3 look_at(const Vector3d& eye, const Vector3d& target, const Vector3d& up) {
  const Vector3d forward = target - eye;
  if (!(forward.norm() > 1e-12)) throw Error("look_at: expected the eye and the target to differ");
  const Vector3d z = forward.normalized();
  const Vector3d x_raw = z.cross(up);
  if (!(x_raw.norm() > 1e-9)) throw Error("look_at: expected a view direction not parallel to 'up'");
  const Vector3d x = x_raw.normalized();
  const Vector3d y = z.cross(x);
  Eigen::Matrix3d R;
  R.col(0) = x;
  R.col(1) = y;
  R.col(2) = z;
  return SE3(R, eye);
}

std::vector<SE3> ring_poses(const Vector3d& centre, double distance_m, int n, double elevation_rad) {
  if (n <= 0 || !(distance_m > 0.0)) throw Error("ring_poses: expected n > 0 and distance_m > 0");
  std::vector<SE3> poses;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * kPi * k / n;
    const Vector3d eye = centre + distance_m * Vector3d(std::cos(elevation_rad) * std::cos(a),
                                                        std::cos(elevation_rad) * std::sin(a), std::sin(elevation_rad));
    poses.push_back(look_at(eye, centre));
  }
  return poses;
}

std::vector<SE3> hemisphere_poses(const Vector3d& centre, double distance_m, int n) {
  if (n <= 0 || !(distance_m > 0.0)) throw Error("hemisphere_poses: expected n > 0 and distance_m > 0");
  std::vector<SE3> poses;
  const double golden = kPi * (3.0 - std::sqrt(5.0));
  const double s_lo = std::sin(10.0 * kPi / 180.0), s_hi = std::sin(80.0 * kPi / 180.0);
  for (int k = 0; k < n; ++k) {
    // Uniform in sin(elevation) = uniform in area on the sphere band.
    const double s = s_lo + (s_hi - s_lo) * (k + 0.5) / n;
    const double c = std::sqrt(1.0 - s * s);
    const double a = golden * k;
    poses.push_back(look_at(centre + distance_m * Vector3d(c * std::cos(a), c * std::sin(a), s), centre));
  }
  return poses;
}

}  // namespace hf::datasets
