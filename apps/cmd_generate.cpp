// `hashfusion generate`: writes a synthetic RGB-D sequence with exact ground truth as a TUM RGB-D folder, with a
// progress line. The folder appears whole or not at all (datasets/tum_writer.h); Ctrl-C or SIGTERM stops it, removes
// the partial build and exits 130 / 143 (apps/interrupt.h), leaving any previous output as it was.
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/progress.h"
#include "io/mesh_file.h"
#include "datasets/mesh_orbit.h"
#include "datasets/presets.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/tum_writer.h"

namespace hf::apps {

namespace {

struct GenerateArgs {
  std::string preset = datasets::default_preset_name();
  int frames = 300;
  std::uint64_t seed = 0;
  std::string out;
  std::string camera = "ros";
  bool no_noise = false;
  bool force = false;
  // --mesh: an orbit around a triangle mesh (datasets/mesh_orbit.h) instead of a preset.
  std::string mesh;
  double mesh_scale = 1.0, orbit_distance_m = 0.45, elevation_deg = 10.0, max_incidence_deg = 70.0;
  std::vector<double> orbit_start{0, 1, 0}, up{0, 0, 1};
};

// A camera preset name, else a camera file (PinholeCamera::load: JSON or "key value" text).
PinholeCamera camera_from_argument(const std::string& camera) {
  for (const auto& name : PinholeCamera::preset_names())
    if (name == camera) return PinholeCamera::preset(name);
  if (!std::filesystem::exists(camera)) {
    std::string known;
    for (const auto& n : PinholeCamera::preset_names()) known += (known.empty() ? "" : ", ") + n;
    throw Error("--camera '" + camera + "': neither a camera preset (" + known + ") nor an existing camera file");
  }
  return PinholeCamera::load(camera);
}

// Writes the folder with a progress line; Ctrl-C or SIGTERM removes the partial build (datasets/tum_writer.h).
template <class Sequence>
void write_folder(const Sequence& sequence, int frames, const GenerateArgs& a) {
  datasets::TumWriteOptions write;
  write.overwrite = a.force;
  // Said here with the flag that replaces it: `hashfusion generate` twice writes out/generate twice.
  std::error_code ec;
  if (!a.force && std::filesystem::exists(std::filesystem::symlink_status(a.out, ec)))
    throw Error(a.out + ": already exists (choose another --out, or --force to replace an earlier generate's output)");
  InterruptGuard guard;
  Progress progress("generate", frames);
  write.progress = [&](int done, int) {
    progress.update(done);
    guard.exit_if_interrupted("nothing written to " + a.out + " (the partial folder is removed)");
  };
  datasets::write_tum_folder(sequence, a.out, write);
  progress.finish();
}

// The mesh, scaled to metres and centred at its vertices' centroid, seen from an orbit around it.
void run_generate_mesh(const GenerateArgs& a) {
  TriangleMesh mesh = read_mesh_file(a.mesh);
  if (mesh.vertices.empty() || mesh.triangles.empty()) throw Error(a.mesh + ": no triangles to render");
  if (!(a.mesh_scale > 0) || !std::isfinite(a.mesh_scale)) throw Error("--mesh-scale: must be positive");
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& v : mesh.vertices) centroid += v.cast<double>();
  centroid /= double(mesh.vertices.size());
  for (auto& v : mesh.vertices) v = (a.mesh_scale * (v.cast<double>() - centroid)).cast<float>();
  datasets::MeshOrbitOptions orbit;
  orbit.frames = a.frames;
  orbit.distance_m = a.orbit_distance_m;
  orbit.elevation_deg = a.elevation_deg;
  orbit.start_world = Eigen::Vector3d(a.orbit_start[0], a.orbit_start[1], a.orbit_start[2]);
  orbit.up_world = Eigen::Vector3d(a.up[0], a.up[1], a.up[2]);
  orbit.camera = camera_from_argument(a.camera);
  orbit.seed = a.seed;
  if (a.no_noise) orbit.noise = datasets::NoiseOptions::none();
  orbit.noise.max_incidence_deg = a.max_incidence_deg;
  orbit.validate();
  datasets::TumSequence seq;
  seq.frames = a.frames;
  seq.camera = orbit.camera;
  seq.list_name = "mesh orbit " + std::filesystem::path(a.mesh).filename().string() + " seed " + std::to_string(a.seed);
  seq.trajectory_name = "a mesh orbit around '" + std::filesystem::path(a.mesh).filename().string() + "' (centred at its centroid, x " +
                        std::to_string(a.mesh_scale) + " m per unit)";
  seq.timestamp_s = datasets::mesh_orbit_timestamp_s;
  seq.frame = [&](int i) { return datasets::mesh_orbit_frame(mesh, orbit, i); };
  write_folder(seq, a.frames, a);
  std::cout << "wrote " << a.frames << " frames of an orbit around " << a.mesh << " (seed " << a.seed << (a.no_noise ? ", no noise" : "")
            << ") to " << a.out << "\n";
}

void run_generate(const GenerateArgs& a) {
  if (!a.mesh.empty()) return run_generate_mesh(a);
  datasets::SyntheticOptions options;
  options.preset = a.preset;
  options.frames = a.frames;
  options.seed = a.seed;
  options.camera = camera_from_argument(a.camera);
  options.noise_enabled = !a.no_noise;
  const datasets::SyntheticSequence sequence(options);  // validates preset and frame count
  write_folder(sequence, sequence.size(), a);
  std::cout << "wrote " << sequence.size() << " frames of synthetic '" << a.preset << "' (seed " << a.seed
            << (a.no_noise ? ", no noise" : "") << ") to " << a.out << "\n";
}

}  // namespace

void add_generate_command(CLI::App& app) {
  auto args = std::make_shared<GenerateArgs>();
  std::string names;
  for (const auto& n : datasets::preset_names()) names += (names.empty() ? "" : ", ") + n;
  CLI::App* cmd = app.add_subcommand(
      "generate", "Write a synthetic RGB-D sequence with exact ground truth as a TUM RGB-D folder");
  cmd->add_option("--preset", args->preset, "Scene and trajectory: " + names)->capture_default_str();
  cmd->add_option("--frames", args->frames, "Number of frames (30 Hz)")->check(synthetic_frames_range())
      ->capture_default_str();
  cmd->add_option("--seed", args->seed, "Sensor-noise seed; the same seed gives identical files")
      ->check(seed_range())
      ->capture_default_str();
  add_out_option(cmd, args->out, "Output folder (must not exist unless --force)");
  cmd->add_option("--camera", args->camera, "Camera preset name or camera file (resolution and intrinsics)")->capture_default_str();
  cmd->add_flag("--no-noise", args->no_noise, "Exact depth and colour: no sensor model");
  cmd->add_flag("--force", args->force, "Replace an existing output folder (only one a previous generate wrote)");
  auto* input = cmd->add_option("--input", args->mesh, "Render an orbit around this .ply / .obj mesh instead of a preset");
  add_deprecated_alias(cmd, input, "--mesh", args->mesh);
  cmd->add_option("--mesh-scale", args->mesh_scale, "--input MESH: metres per mesh unit")->capture_default_str();
  cmd->add_option("--orbit-distance-m", args->orbit_distance_m, "--input MESH: camera distance from the centroid")->capture_default_str();
  cmd->add_option("--elevation-deg", args->elevation_deg, "--input MESH: orbit elevation above the plane normal to --up")->capture_default_str();
  cmd->add_option("--orbit-start", args->orbit_start, "--input MESH: direction of the first camera from the centroid (mesh axes), x,y,z")
      ->delimiter(',')->expected(3);
  cmd->add_option("--up", args->up, "--input MESH: the orbit's up direction (mesh axes), x,y,z")->delimiter(',')->expected(3);
  cmd->add_option("--max-incidence-deg", args->max_incidence_deg,
                  "--input MESH: depth beyond this incidence angle is dropped (grazing pixels fuse into fins; bench/results/head.md)")
      ->capture_default_str();
  cmd->callback([args] { run_generate(*args); });
}

}  // namespace hf::apps
