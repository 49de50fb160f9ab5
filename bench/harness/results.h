// The benchmark's results: one row per (method, input) run, the won-lost-tie comparison of the methods, the
// speed/error Pareto front, and the three result files (results.csv, results.json, results.md).
//
// Comparison rules (the form of Table 1 of the registration report, Stotko 2016, eq. 76):
// - A run is COMPARABLE on an input when it finished, has an ATE RMSE, and lost at most kMaxLostFraction of its
//   frames (a trajectory that skips most frames has an ATE over too little of the sequence to mean anything).
//   Otherwise it counts as LOST on that input. Inputs without ground truth take no part in the comparison.
// - Won-lost-tie of method A against B over the inputs both were run on: a TIE when both are lost or both ATEs
//   are within kTieRelative (5%) of the larger one (|a - b| <= 0.05 max(a, b)); otherwise the lower ATE wins, and a
//   comparable run wins against a lost one.
// - Mean error ME(L) = the mean ATE RMSE over the inputs on which BOTH methods of a pair are comparable, so each
//   ratio compares the two on the same inputs.
// - Table cell (row r, column c): below the diagonal (r > c) the W-L-T of the COLUMN method against the ROW
//   method; above it (r < c) the quotient ME(L_r) / ME(L_c) ("-" when they share no comparable input).
//
// Thread-safety: pure functions and value types. Writers throw hf::Error naming the file; readers throw
// hf::ParseError "FILE:LINE: expected ..." for malformed files.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <vector>

namespace hf::bench {

inline constexpr double kTieRelative = 0.05;
inline constexpr double kMaxLostFraction = 0.5;

// Mean milliseconds per processed frame, per pipeline stage; total = their sum.
struct StageMs {
  double read = 0, preprocess = 0, track = 0, integrate = 0, raycast = 0, total = 0;
};

struct RunRow {
  std::string method;      // registration name, or the peer's name ("gicp", "ndt") for peers
  bool peer = false;       // a reference implementation (PCL) rather than a hashfusion registration
  std::string input;       // the input's label (e.g. "synthetic:wall", "rgbd_dataset_freiburg1_rpy")
  std::string source;      // FrameSource::name()
  bool failed = false;     // the run threw; `error` says why (one line)
  std::string error;
  bool interrupted = false;
  long frames = 0, frames_bad = 0, frames_lost = 0;
  // Tracking recovery (slam/sequence_run.h RunSummary): frames with a pose / frames, runs of lost frames, and the
  // slowest frame (loop-closure work included). Peers: coverage from their lost frames, worst frame measured too.
  double coverage = 0.0;
  long lost_spells = 0, longest_lost_spell = 0;
  double worst_frame_ms = 0.0;
  std::optional<double> ate_rmse_m, rpe_trans_m_per_s, rpe_rot_deg_per_s;
  // RPE between consecutive estimated poses (bench/harness/frame_rpe.h: evaluate_rpe.py --delta 1 --delta_unit f),
  // RMSE in metres / degrees per frame pair: exists where the 1 s RPE does not fit (runs shorter than 1 s).
  std::optional<double> rpe_frame_trans_m, rpe_frame_rot_deg;
  double fps = 0.0;        // frames / sum of per-frame stage times
  StageMs ms;
  double wall_s = 0.0;     // the whole run, including opening the input

  // "combined" or "gicp (peer)": the name tables and plots show.
  std::string display_name() const;
  // See the comparison rules above.
  bool comparable() const;
};

struct MachineInfo {
  std::string commit = "unknown", command_line, cpu_model = "unknown", date_utc;
  unsigned cores = 0;
};
// The running machine and time: `git rev-parse HEAD` in `source_dir` (else "unknown"), nproc, /proc/cpuinfo's
// model name, the current UTC date. Never throws.
MachineInfo current_machine(const std::string& source_dir, const std::string& command_line);

struct BenchResults {
  MachineInfo machine;
  std::vector<std::string> methods;   // row/column order of the tables: hashfusion methods, then peers
  std::vector<std::string> inputs;    // input labels in run order
  std::vector<std::string> notes;     // skipped folders and other remarks, one line each
  std::vector<RunRow> runs;
  std::string settings;               // one line: voxel, backend, frame limits, peers
};

enum class Outcome { win, loss, tie };
// The error a table compares: ATE RMSE (m), translational RPE over 1 s (m/s) or translational RPE per frame pair
// (m, delta = 1 frame), all as the TUM tools compute them. The rules above apply to each; a run is comparable by an
// RPE when it is comparable and has that RPE.
enum class ErrorMetric { ate_rmse, rpe_translation, rpe_frame_translation };
// "ATE RMSE", "translational RPE (1 s)", "translational RPE (1 frame)".
std::string metric_name(ErrorMetric metric);
std::optional<double> run_error(const RunRow& run, ErrorMetric metric);
bool comparable_by(const RunRow& run, ErrorMetric metric);
// The outcome for `a` against `b` on one input (rules above).
Outcome compare_runs(const RunRow& a, const RunRow& b, ErrorMetric metric = ErrorMetric::ate_rmse);

struct WltCell {
  int wins = 0, losses = 0, ties = 0;  // of the column method against the row method
};

struct WltTable {
  std::vector<std::string> methods;           // display names, row and column order
  // wlt[r][c]: W-L-T of method c against method r over the inputs both ran on (meaningful for r != c).
  std::vector<std::vector<WltCell>> wlt;
  // ratio[r][c] = ME(r) / ME(c) over the inputs where both are comparable; nullopt when there is none.
  std::vector<std::vector<std::optional<double>>> ratio;
  std::vector<std::vector<int>> common_inputs;  // inputs behind ratio[r][c]
  int inputs = 0;                                // inputs with ground truth taking part
  std::string metric = "ATE RMSE";               // the error compared (metric_name)
};

// Methods are identified by display_name(); `order` gives the row order (names missing from the runs are kept
// with empty rows). Runs without ground truth (no ATE and not failed, on an input where no run has an ATE) are
// left out.
WltTable won_lost_tie(const std::vector<RunRow>& runs, const std::vector<std::string>& order,
                      ErrorMetric metric = ErrorMetric::ate_rmse);
// Markdown of the table in the report's form, with the rule underneath.
std::string format_wlt_markdown(const WltTable& table);

// Indices into `points` (x = cost, y = error; both to be minimised) of the non-dominated points, sorted by x
// ascending. A point is dominated when another has x <= and y <= with one strictly smaller; exact duplicates are
// all kept. Points with non-finite coordinates are never on the front.
struct ParetoPoint {
  double x = 0.0, y = 0.0;
};
std::vector<size_t> pareto_front(const std::vector<ParetoPoint>& points);

// Per method over all inputs (the overall speed/error plot and the summary table): mean ATE over the inputs where
// the method is comparable, mean ms per frame over the runs that finished.
struct MethodSummary {
  std::string name;  // display name
  bool peer = false;
  int inputs_run = 0, inputs_comparable = 0, runs_failed = 0;
  std::optional<double> mean_ate_m, mean_ms_per_frame;
  long frames = 0, frames_lost = 0;
};
std::vector<MethodSummary> summarize_methods(const std::vector<RunRow>& runs, const std::vector<std::string>& order);

// results.csv: a header line, then one line per run (RFC 4180 quoting; missing numbers are empty fields; numbers
// in shortest round-trip form).
std::string results_to_csv(const std::vector<RunRow>& runs);
std::vector<RunRow> results_from_csv(const std::string& text, const std::string& file);

// results.json: {"machine": {...}, "settings", "methods", "inputs", "notes", "runs": [...],
//                "won_lost_tie": {"methods", "wlt", "ratio", "rule"}, "won_lost_tie_rpe": the same by RPE over 1 s,
//                "won_lost_tie_rpe_frame": by RPE per frame pair};
// null for missing numbers.
nlohmann::json results_to_json(const BenchResults& results);
BenchResults results_from_json(const nlohmann::json& j, const std::string& file);

// results.md: machine and command, one table per input, the W-L-T table and links to the plots.
std::string results_to_markdown(const BenchResults& results, const std::vector<std::string>& plot_files);

// Writes results.csv, results.json and results.md into `dir` atomically; returns their paths.
std::vector<std::string> write_results(const std::string& dir, const BenchResults& results,
                                       const std::vector<std::string>& plot_files);

}  // namespace hf::bench
