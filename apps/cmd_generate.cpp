// `hashfusion generate`: writes a synthetic RGB-D sequence with exact ground truth as a TUM RGB-D folder, with a
// progress line. The folder appears whole or not at all (datasets/tum_writer.h); Ctrl-C or SIGTERM stops it, removes
// the partial build and exits 130 / 143 (apps/interrupt.h), leaving any previous output as it was.
#include <CLI/CLI.hpp>
#include <cstdint>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "apps/commands.h"
#include "apps/interrupt.h"
#include "core/camera.h"
#include "core/error.h"
#include "core/progress.h"
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

void run_generate(const GenerateArgs& a) {
  datasets::SyntheticOptions options;
  options.preset = a.preset;
  options.frames = a.frames;
  options.seed = a.seed;
  options.camera = camera_from_argument(a.camera);
  options.noise_enabled = !a.no_noise;
  const datasets::SyntheticSequence sequence(options);  // validates preset and frame count
  datasets::TumWriteOptions write;
  write.overwrite = a.force;
  InterruptGuard guard;
  Progress progress("generate", sequence.size());
  write.progress = [&](int done, int) {
    progress.update(done);
    guard.exit_if_interrupted("nothing written to " + a.out + " (the partial folder is removed)");
  };
  datasets::write_tum_folder(sequence, a.out, write);
  progress.finish();
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
  cmd->add_option("--frames", args->frames, "Number of frames (30 Hz)")->capture_default_str();
  cmd->add_option("--seed", args->seed, "Sensor-noise seed; the same seed gives identical files")
      ->capture_default_str();
  cmd->add_option("--out", args->out, "Output folder (must not exist unless --force)")->required();
  cmd->add_option("--camera", args->camera, "Camera preset name or camera file (resolution and intrinsics)")->capture_default_str();
  cmd->add_flag("--no-noise", args->no_noise, "Exact depth and colour: no sensor model");
  cmd->add_flag("--force", args->force, "Replace an existing output folder (only one a previous generate wrote)");
  cmd->callback([args] { run_generate(*args); });
}

}  // namespace hf::apps
