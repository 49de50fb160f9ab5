// `hashfusion bench`: every registration (and the PCL peers) on every input, with one pipeline configuration;
// results.{md,json,csv}, won-lost-tie tables and speed/error plots (bench/harness/harness.h, bench/README.md).
#include <CLI/CLI.hpp>
#include <sys/stat.h>

#include <filesystem>
#include <functional>
#include <iostream>
#include <memory>
#include <sstream>
#include <tuple>

#include <nlohmann/json.hpp>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/registration_list.h"
#include "bench/harness/harness.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "core/output_transaction.h"

namespace hf::apps {
namespace {

struct BenchCliOptions {
  std::vector<std::string> inputs;
  std::vector<std::string> merge;  // --merge DIR...: combine earlier results instead of running
  std::string registration = "all";
  std::string peers = "all";
  std::string loop_closure = "on";
  std::string out;  // --out: out/bench unless given (add_out_option)
  double voxel_m = 0.01;
  std::string backend = "cpu";
  long max_frames = 0;
  int synthetic_frames = 300;
  std::uint64_t seed = 0;
  float peer_voxel_m = 0.04f;
  float ndt_resolution_m = 0.2f;
  int peer_pixel_stride = 2;
  std::string config_file;
  std::string camera;  // --camera PRESET|FILE: every input's camera (default: chosen per dataset, 'ros' for synthetic)
  int tracking_level = -1;
  std::string shard;      // --shard K/N: slice K of N of the runs (bench/harness/harness.h)
  bool list_runs = false;  // --list-runs: print the runs, one per line, and run nothing
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

// What the bench run that last wrote `out` wrote there: results.{md,json,csv}, its plots and trajectories/, when
// its results.json is a bench's; none for any other folder, so a user's files are always carried over.
std::function<bool(const std::string&)> previous_bench_run_wrote(const std::string& out) {
  bool bench_folder = false;
  nlohmann::json j;
  if (read_previous_manifest(out + "/results.json", &j)) {
    try {
      bench::results_from_json(j, out + "/results.json");
      bench_folder = true;
    } catch (const std::exception&) {
      bench_folder = false;
    }
  }
  return [bench_folder](const std::string& name) {
    return bench_folder && (name == "results.md" || name == "results.json" || name == "results.csv" ||
                            name == "trajectories" || name == "synthetic_cache" ||
                            (name.starts_with("speed_vs_error") && name.ends_with(".png")));
  };
}

// A path the harness wrote into the transaction's private folder, as it reads once the folder is in place.
std::string final_path(const std::string& f, const OutputTransaction& outputs) {
  const std::string& staged = outputs.folder();
  const std::string rest = f.compare(0, staged.size(), staged) == 0 ? f.substr(staged.size()) : f;
  return std::filesystem::absolute(outputs.target() + rest).string();
}

void run_bench_command(const BenchCliOptions& c) {
  // The outputs as one transaction (core/output_transaction.h), as `run`'s: built in a private folder beside --out
  // and exchanged with it at the end, so an interruption or a failure leaves the previous set or the new one.
  if (!c.merge.empty()) {
    OutputTransaction outputs(c.out);
    const bench::BenchReport report =
        bench::merge_bench(c.merge, outputs.folder(), bench::build_source_dir(), c.command_line);
    outputs.commit(previous_bench_run_wrote(outputs.target()));
    std::cout << "outputs:\n";
    for (const std::string& f : report.files) std::cout << "  " << final_path(f, outputs) << "\n";
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
  o.camera = c.camera;
  o.tracking_level = c.tracking_level;
  o.max_frames = c.max_frames;
  o.synthetic_frames = c.synthetic_frames;
  o.seed = c.seed;
  o.peer.voxel_m = c.peer_voxel_m;
  o.peer.ndt_resolution_m = c.ndt_resolution_m;
  o.peer.pixel_stride = c.peer_pixel_stride;
  o.command_line = c.command_line;
  o.source_dir = bench::build_source_dir();
  if (!c.shard.empty()) std::tie(o.shard_index, o.shard_count) = bench::parse_shard(c.shard);
  if (c.list_runs) {
    // One line per run, "INDEX<TAB>INPUT<TAB>METHOD": what --shard K/N slices, and the array size of one run per task.
    const std::vector<bench::PlannedRun> runs = bench::plan_runs(o);
    for (size_t k = 0; k < runs.size(); ++k) std::cout << k << "\t" << runs[k].input << "\t" << runs[k].method << "\n";
    return;
  }
  OutputTransaction outputs(c.out);  // listing the runs writes nothing, so takes no lock
  o.out = outputs.folder();
  InterruptGuard guard;  // Ctrl-C / SIGTERM: finish the current run, write the results, exit 130 / 143
  o.stop = guard.flag();
  const bench::BenchReport report = bench::run_bench(o);
  outputs.commit(previous_bench_run_wrote(outputs.target()));

  std::cout << "outputs:\n";
  size_t shown = 0;
  for (const std::string& f : report.files) {
    if (f.find("/trajectories/") != std::string::npos) continue;
    std::cout << "  " << final_path(f, outputs) << "\n";
    ++shown;
  }
  if (shown < report.files.size()) {
    std::cout << "  " << std::filesystem::absolute(outputs.target() + "/trajectories").string() << "/ ("
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
  cmd->add_option("--registration", opts->registration, "all, or a comma-separated list of registration methods: " + registration_list())
      ->capture_default_str();
  cmd->add_option("--peers", opts->peers, "peers: all, none, or a comma-separated list of gicp, ndt (PCL), o3d-icp, o3d-colored-icp, o3d-rgbd "
                  "(Open3D, where built)")
      ->capture_default_str();
  cmd->add_option("--loop-closure", opts->loop_closure,
                  "loop-closure modes each registration runs in: all, or a list of off, on, global (run --global)")
      ->capture_default_str();
  add_out_option(cmd, opts->out, "output folder");
  cmd->add_option("--shard", opts->shard,
                  "K/N: run only slice K (from 0) of N of the runs --list-runs lists (a job array task; "
                  "`bench --merge` of the N --out folders in K order gives the single run's tables)");
  cmd->add_flag("--list-runs", opts->list_runs,
                "print the runs (INDEX, INPUT, METHOD per line, tab-separated) that --shard slices, and run nothing");
  cmd->add_option("--voxel-m", opts->voxel_m, "TSDF voxel size in metres")->check(voxel_m_range())
      ->capture_default_str();
  cmd->add_option("--backend", opts->backend, "reduction backend: cpu | opencl")->capture_default_str();
  cmd->add_option("--config", opts->config_file, "JSON pipeline configuration shared by every run (see hashfusion run)");
  cmd->add_option("--camera", opts->camera,
                  "camera preset name or camera file for every input (default: chosen per dataset; synthetic: ros)");
  cmd->add_option("--tracking-level", opts->tracking_level,
                  "pyramid level tracking starts at (0 full, 1 half resolution); default: the configuration's")
      ->check(tracking_level_range());
  cmd->add_option("--max-frames", opts->max_frames, "frames per run (0 = all)")
      ->check(non_negative())
      ->capture_default_str();
  cmd->add_option("--synthetic-frames", opts->synthetic_frames, "frames rendered per synthetic preset")
      ->check(synthetic_frames_range(2))
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "noise seed of the synthetic: inputs")->check(seed_range())->capture_default_str();
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
      if (!opts->shard.empty() || opts->list_runs)
        throw Error("bench: --shard and --list-runs slice the runs of --input, not a --merge");
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
    if (!opts->camera.empty()) line += " --camera " + quote_arg(opts->camera);
    if (!opts->shard.empty()) line += " --shard " + quote_arg(opts->shard);
    if (opts->tracking_level >= 0) line += " --tracking-level " + std::to_string(opts->tracking_level);
    if (opts->seed != 0) line += " --seed " + std::to_string(opts->seed);
    opts->command_line = line;
    run_bench_command(*opts);
  });
}

}  // namespace hf::apps
