// `hashfusion bench`: every registration (and the PCL peers) on every input, with one pipeline configuration;
// results.{md,json,csv}, won-lost-tie tables and speed/error plots (bench/harness/harness.h, bench/README.md).
#include <CLI/CLI.hpp>
#include <filesystem>
#include <iostream>
#include <memory>
#include <sstream>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "bench/harness/harness.h"
#include "core/error.h"

namespace hf::apps {
namespace {

struct BenchCliOptions {
  std::vector<std::string> inputs;
  std::vector<std::string> merge;  // --merge DIR...: combine earlier results instead of running
  std::string registration = "all";
  std::string peers = "all";
  std::string loop_closure = "on";
  std::string out = "out/bench";
  double voxel_m = 0.01;
  std::string backend = "cpu";
  long max_frames = 0;
  int synthetic_frames = 300;
  float peer_voxel_m = 0.04f;
  float ndt_resolution_m = 0.2f;
  int peer_pixel_stride = 2;
  std::string config_file;
  int tracking_level = -1;
  std::string command_line;
};

std::string quote_arg(const std::string& a) {
  if (!a.empty() && a.find_first_of(" \t'\"\\$`*?") == std::string::npos) return a;
  std::string q = "'";
  for (char ch : a) q += ch == '\'' ? std::string("'\\''") : std::string(1, ch);
  return q + "'";
}

std::string number(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void run_bench_command(const BenchCliOptions& c) {
  if (!c.merge.empty()) {
    const bench::BenchReport report = bench::merge_bench(c.merge, c.out, bench::build_source_dir(), c.command_line);
    std::cout << "outputs:\n";
    for (const std::string& f : report.files) std::cout << "  " << std::filesystem::absolute(f).string() << "\n";
    return;
  }
  bench::BenchOptions o;
  o.inputs = c.inputs;
  o.registrations = bench::resolve_registrations(c.registration);
  o.peers = bench::resolve_peers(c.peers);
  o.loop_closure_modes = bench::resolve_loop_closure_modes(c.loop_closure);
  o.out = c.out;
  o.voxel_m = c.voxel_m;
  o.backend = c.backend;
  o.config_file = c.config_file;
  o.tracking_level = c.tracking_level;
  o.max_frames = c.max_frames;
  o.synthetic_frames = c.synthetic_frames;
  o.peer.voxel_m = c.peer_voxel_m;
  o.peer.ndt_resolution_m = c.ndt_resolution_m;
  o.peer.pixel_stride = c.peer_pixel_stride;
  o.command_line = c.command_line;
  o.source_dir = bench::build_source_dir();
  InterruptGuard guard;  // Ctrl-C / SIGTERM: finish the current run, write the results, exit 130 / 143
  o.stop = guard.flag();
  const bench::BenchReport report = bench::run_bench(o);

  std::cout << "outputs:\n";
  size_t shown = 0;
  for (const std::string& f : report.files) {
    if (f.find("/trajectories/") != std::string::npos) continue;
    std::cout << "  " << std::filesystem::absolute(f).string() << "\n";
    ++shown;
  }
  if (shown < report.files.size()) {
    std::cout << "  " << std::filesystem::absolute(o.out + "/trajectories").string() << "/ ("
              << report.files.size() - shown << " trajectories)\n";
  }
  guard.exit_if_interrupted("results cover the runs finished so far");
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto opts = std::make_shared<BenchCliOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench", "Run every registration (and the PCL / Open3D peers) on every input; write results.{md,json,csv} and plots");
  cmd->add_option("--input", opts->inputs,
                  "synthetic:PRESET, synthetic:all, a TUM / 7-Scenes folder, or a folder containing such datasets "
                  "(searched recursively); repeatable; required unless --merge")
      ->expected(1, -1);
  cmd->add_option("--merge", opts->merge,
                  "instead of running: combine the results.json of these earlier --out folders into --out (a later "
                  "folder's row replaces an earlier one of the same method and input)")
      ->expected(1, -1);
  cmd->add_option("--registration", opts->registration, "all, or a comma-separated list of registration methods")
      ->capture_default_str();
  cmd->add_option("--peers", opts->peers, "peers: all, none, or a comma-separated list of gicp, ndt (PCL), o3d-icp, o3d-colored-icp, o3d-rgbd "
                  "(Open3D, where built)")
      ->capture_default_str();
  cmd->add_option("--loop-closure", opts->loop_closure,
                  "loop-closure modes each registration runs in: all, or a list of off, on, global (run --global)")
      ->capture_default_str();
  cmd->add_option("--out", opts->out, "output folder")->capture_default_str();
  cmd->add_option("--voxel-m", opts->voxel_m, "TSDF voxel size in metres")->check(voxel_m_range())
      ->capture_default_str();
  cmd->add_option("--backend", opts->backend, "reduction backend: cpu | opencl")->capture_default_str();
  cmd->add_option("--config", opts->config_file, "JSON pipeline configuration shared by every run (see hashfusion run)");
  cmd->add_option("--tracking-level", opts->tracking_level,
                  "pyramid level tracking starts at (0 full, 1 half resolution); default: the configuration's")
      ->check(tracking_level_range());
  cmd->add_option("--max-frames", opts->max_frames, "frames per run (0 = all)")
      ->check(non_negative())
      ->capture_default_str();
  cmd->add_option("--synthetic-frames", opts->synthetic_frames, "frames rendered per synthetic preset")
      ->check(in_range(2, 100000))
      ->capture_default_str();
  cmd->add_option("--peer-voxel-m", opts->peer_voxel_m, "voxel-grid size of the peers' clouds in metres")
      ->check(positive())
      ->capture_default_str();
  cmd->add_option("--ndt-resolution-m", opts->ndt_resolution_m, "NDT cell size in metres")
      ->check(positive())
      ->capture_default_str();
  cmd->add_option("--peer-pixel-stride", opts->peer_pixel_stride, "peers back-project every k-th pixel")
      ->check(in_range(1, 64))
      ->capture_default_str();
  cmd->callback([opts] {
    if (opts->inputs.empty() && opts->merge.empty()) throw Error("bench: --input is required (or --merge DIR... to combine earlier results)");
    if (!opts->merge.empty()) {
      if (!opts->inputs.empty()) throw Error("bench: --merge runs nothing: give --input or --merge, not both");
      std::string line = "hashfusion bench --merge";
      for (const std::string& d : opts->merge) line += " " + quote_arg(d);
      opts->command_line = line + " --out " + quote_arg(opts->out);
      run_bench_command(*opts);
      return;
    }
    // The command line as typed, for the report (CLI11 keeps no copy of argv).
    std::string line = "hashfusion bench";
    for (const std::string& i : opts->inputs) line += " --input " + quote_arg(i);
    line += " --registration " + quote_arg(opts->registration) + " --peers " + quote_arg(opts->peers) +
            " --out " + quote_arg(opts->out) + " --voxel-m " + number(opts->voxel_m) + " --backend " +
            quote_arg(opts->backend) + " --max-frames " + std::to_string(opts->max_frames) +
            " --synthetic-frames " + std::to_string(opts->synthetic_frames);
    if (!opts->config_file.empty()) line += " --config " + quote_arg(opts->config_file);
    if (opts->tracking_level >= 0) line += " --tracking-level " + std::to_string(opts->tracking_level);
    opts->command_line = line;
    run_bench_command(*opts);
  });
}

}  // namespace hf::apps
