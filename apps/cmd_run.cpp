// `hashfusion run`: the main job. A dataset (TUM or 7-Scenes folder, or synthetic:PRESET generated on the fly) goes
// through the SLAM pipeline (slam/pipeline.h) and the outputs land in --out: trajectory.txt, mesh.ply, report.json,
// report.md, render.png and, with ground truth, trajectory.png. Ctrl-C stops after the current frame and still
// writes every output for the frames processed.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>

#include "apps/commands.h"
#include "core/error.h"
#include "datasets/synthetic_source.h"
#include "io/dataset.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"

namespace hf::apps {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted.store(true); }

struct RunOptions {
  std::string input = "synthetic:room";
  std::string out = "out/run";
  std::string registration = "combined";
  std::string backend = "cpu";
  std::string camera;
  std::string config_file;
  double voxel_m = 0.01;
  int tracking_level = -1;  // -1: the configuration's
  long max_frames = 0;  // 0 = all
  int synthetic_frames = 90;
  std::uint64_t seed = 0;
};

std::unique_ptr<FrameSource> open_input(const RunOptions& o) {
  if (datasets::is_synthetic_input(o.input)) {
    datasets::SyntheticOptions s;
    s.frames = o.synthetic_frames;
    s.seed = o.seed;
    if (!o.camera.empty()) s.camera = camera_from_option(o.camera).camera;
    return datasets::open_synthetic_input(o.input, s);
  }
  DatasetOptions d;
  d.camera = o.camera;
  return open_dataset(o.input, d);
}

// The configuration: defaults, then the --config file, then the flags given on the command line.
slam::PipelineConfig make_config(const RunOptions& o, const CLI::App& cmd) {
  slam::PipelineConfig c = o.config_file.empty() ? slam::PipelineConfig{} : slam::load_config(o.config_file);
  if (o.config_file.empty() || cmd.count("--registration")) c.registration = o.registration;
  if (o.config_file.empty() || cmd.count("--backend")) c.backend = o.backend;
  if (o.config_file.empty() || cmd.count("--voxel-m")) c.volume.voxel_m = o.voxel_m;
  if (o.tracking_level >= 0) c.tracking_level = o.tracking_level;
  // A method change on the command line must not inherit another method's options from the file.
  if (cmd.count("--registration") && c.registration_options && !o.config_file.empty()) c.registration_options.reset();
  c.validate();
  return c;
}

void run(const RunOptions& o, const CLI::App& cmd) {
  const slam::PipelineConfig config = make_config(o, cmd);
  std::unique_ptr<FrameSource> source = open_input(o);
  if (source->size() == 0) throw Error(o.input + ": the dataset has no frames");
  std::cerr << "input: " << source->name() << ", " << source->size() << " frames\n"
            << "camera: " << source->camera().describe() << " (" << source->camera_origin() << ")\n"
            << "registration: " << config.registration << " (backend " << config.backend << "), voxel "
            << config.volume.voxel_m * 1000.0 << " mm\n";
  slam::Pipeline pipeline(config, source->camera());

  slam::RunControl control;
  control.max_frames = o.max_frames;
  control.stop = &g_interrupted;
  control.progress_label = "run";
  g_interrupted.store(false);
  auto previous = std::signal(SIGINT, on_sigint);
  slam::SequenceRun result;
  try {
    result = slam::run_sequence(*source, pipeline, control);
  } catch (...) {
    std::signal(SIGINT, previous);
    throw;
  }
  std::signal(SIGINT, previous);
  if (result.interrupted)
    std::cerr << "interrupted: writing outputs for the " << result.frames.size() << " frames processed\n";
  if (result.frames.empty()) throw Error(o.input + ": no usable frames");

  const slam::RunSummary summary = slam::summarize(result, pipeline, *source, o.input);
  const std::vector<std::string> written = slam::write_run_outputs(o.out, result, summary, pipeline, *source);
  std::cout << "outputs:\n";
  for (const auto& p : written) std::cout << "  " << std::filesystem::absolute(p).string() << "\n";
  std::cout << "frames: " << summary.frames << " (" << summary.frames_lost << " lost, " << summary.frames_bad
            << " unreadable), " << summary.fps << " fps\n";
  if (const auto ate = summary.ate_rmse_m()) std::cout << "ATE RMSE: " << *ate << " m\n";
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto opts = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Track and fuse a dataset; write trajectory, mesh, report and plots");
  cmd->add_option("--input", opts->input, "synthetic:PRESET, a TUM RGB-D folder, or a 7-Scenes folder")
      ->capture_default_str();
  cmd->add_option("--out", opts->out, "output folder")->capture_default_str();
  cmd->add_option("--registration", opts->registration, "registration method, or groundtruth (fusion only)")
      ->capture_default_str();
  cmd->add_option("--backend", opts->backend, "reduction backend: cpu | opencl")->capture_default_str();
  cmd->add_option("--voxel-m", opts->voxel_m, "voxel size in metres")->check(CLI::Range(1e-4, 10.0))
      ->capture_default_str();
  cmd->add_option("--tracking-level", opts->tracking_level,
                  "pyramid level tracking starts at (0 full, 1 half resolution); default: the configuration's")
      ->check(CLI::Range(0, 2));
  cmd->add_option("--camera", opts->camera, "camera preset name or camera file (default: chosen per dataset)");
  cmd->add_option("--config", opts->config_file, "JSON pipeline configuration (report.json's \"config\" form)");
  cmd->add_option("--max-frames", opts->max_frames, "stop after N frames (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--synthetic-frames", opts->synthetic_frames, "frames of a synthetic: input")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "noise seed of a synthetic: input")->capture_default_str();
  cmd->callback([opts, cmd] { run(*opts, *cmd); });
}

}  // namespace hf::apps
