// `hashfusion bench`: every registration on every input, in one process, with one PipelineConfig.
//
//   BenchOptions o;  o.inputs = {"synthetic:all", "../shared/data"};  o.registrations = resolve_registrations("all");
//   BenchReport r = run_bench(o);   // writes o.out/results.{csv,json,md} and speed_vs_error*.png
//
// Per input (bench/harness/inputs.h), in order: a synthetic preset is rendered once into a temporary TUM folder
// (o.out/synthetic_cache/PRESET, removed after its runs), so every method reads the same frames from disk the way
// it reads a real dataset; then each registration runs on a fresh slam::Pipeline (slam::run_sequence +
// slam::summarize), then each PCL peer (bench/harness/peers.h). A run that throws (e.g. the block pool is
// exhausted) becomes a failed row with its one-line message; the harness carries on. When *stop becomes true the
// current run ends, the rest are skipped, and the results so far are written.
//
// Outputs in o.out (each written atomically): results.csv, results.json, results.md (bench/harness/results.h),
// speed_vs_error.png (all inputs: each method's mean ms per frame against its mean ATE over the inputs it tracked)
// and speed_vs_error_<input>.png per input with ground truth, and trajectories/<input>__<method>.txt (the TUM
// trajectory of each run, for re-evaluation).
#pragma once

#include <atomic>
#include <string>
#include <utility>
#include <vector>

#include "bench/harness/peers.h"
#include "bench/harness/results.h"

namespace hf::bench {

struct BenchOptions {
  std::vector<std::string> inputs;         // --input PATH... (see inputs.h)
  std::vector<std::string> registrations;  // registry names (resolve_registrations)
  std::vector<std::string> peers;          // "gicp", "ndt" (resolve_peers)
  // Loop-closure modes each registration runs in (resolve_loop_closure_modes): "on" (the pipeline's default),
  // "off" (loop_closure.enabled false) and "global" (on, plus Pipeline::finish(true), `run --global`). Each mode
  // is its own column of the tables: the method's name alone for "on", "NAME +global" and "NAME -loops".
  std::vector<std::string> loop_closure_modes = {"on"};
  std::string out = "out/bench";
  double voxel_m = 0.01;
  std::string backend = "cpu";
  // The pipeline settings every run shares (slam::load_config form); empty: the defaults. registration, backend and
  // voxel_m above override the file's; a file's registration_options apply only to the method the file names.
  std::string config_file;
  // Every input's camera, a preset name or a camera file (io/dataset.h DatasetOptions::camera); empty: each dataset's
  // own choice, and synthetic presets render with 640x480 'ros'. Checked before any run (camera_from_option).
  std::string camera;
  int tracking_level = -1;                 // >= 0 overrides the config's tracking_level
  long max_frames = 0;                     // per run, 0 = all
  int synthetic_frames = 300;              // frames rendered per synthetic preset (at most max_frames when set)
  std::uint64_t seed = 0;                  // sensor-noise seed of the synthetic presets (run / generate --seed)
  PeerOptions peer;
  std::string command_line;                // for the report
  std::string source_dir;                  // where `git rev-parse HEAD` runs; empty: commit "unknown"
  const std::atomic<bool>* stop = nullptr;
  bool progress = true;                    // progress bars on stderr (slam::RunControl::progress_label)
  // --shard K/N (a job array, scripts/bench_sweep.slurm): run only slice K of N of the runs plan_runs() lists,
  // the runs [K*U/N, (K+1)*U/N) of U. The results list only the inputs and methods this slice ran, in the single
  // run's order, so `bench --merge` of slices 0..N-1 (in that order) gives the single run's methods, inputs, rows
  // and tables. The default 0/1 is everything.
  int shard_index = 0, shard_count = 1;
};

// One run of a benchmark: a method (its table label: loop_closure_label or "NAME (peer)") on an input.
struct PlannedRun {
  std::string input;   // BenchInput::label
  std::string method;  // the table label
};
// The runs of `options` in the order run_bench makes them: per input (discover_inputs order), each registration
// in each loop-closure mode, then each peer. Discovers the inputs (throws as discover_inputs) but renders and runs
// nothing. `bench --list-runs` prints this list; its length is the N of one run per array task.
std::vector<PlannedRun> plan_runs(const BenchOptions& options);

// "K/N" with 0 <= K < N -> {K, N}. Throws hf::Error naming the text otherwise.
std::pair<int, int> parse_shard(const std::string& text);
// The half-open index range [first, last) of slice k of n over `runs` runs: [k*runs/n, (k+1)*runs/n). Slices are
// contiguous (a slice renders each synthetic input it touches once) and differ in size by at most one.
std::pair<size_t, size_t> shard_range(size_t runs, int k, int n);

// "all" -> registration_names(); else a comma-separated list of registry names (and "groundtruth"). Throws
// hf::Error naming an unknown method and listing the known ones, or for an empty list.
std::vector<std::string> resolve_registrations(const std::string& spec);
// "all" -> {off, on, global}; else a comma-separated subset. Throws hf::Error otherwise.
std::vector<std::string> resolve_loop_closure_modes(const std::string& spec);
// The table label of `method` run in loop-closure `mode` (see BenchOptions::loop_closure_modes).
std::string loop_closure_label(const std::string& method, const std::string& mode);

// "none" -> {}; "all" -> peer_names(); else a comma-separated subset of peer_names(). Throws hf::Error otherwise.
std::vector<std::string> resolve_peers(const std::string& spec);

// The source tree this binary was built from (where `git rev-parse HEAD` names the commit).
std::string build_source_dir();

// A file-name-safe form of a label: letters, digits, '-', '_' and '.' kept, anything else '_'.
std::string file_safe(const std::string& label);

struct BenchReport {
  BenchResults results;
  std::vector<std::string> files;  // every file written, results first
};

// Runs everything (or its --shard slice) and writes the outputs. Throws hf::Error for bad options (a shard with
// more slices than runs included), inputs that cannot be found, or an output folder that cannot be
// created/written; individual runs never make it throw.
BenchReport run_bench(const BenchOptions& options);

// `hashfusion bench --merge DIR... --out OUT`: the rows of earlier runs' DIR/results.json in one table, without
// running anything (e.g. a table's peers or one method re-run later at another commit). A later folder's row
// replaces an earlier one of the same method on the same input; methods and inputs keep their first-seen order
// (hashfusion methods before peers); the notes name each folder's commit, date and command. Writes results.* and
// the plots into `out` (no trajectories). Throws hf::Error for a missing folder or file, hf::ParseError for a
// file that is not a bench results.json.
BenchReport merge_bench(const std::vector<std::string>& dirs, const std::string& out, const std::string& source_dir,
                        const std::string& command_line);

}  // namespace hf::bench
