// `hashfusion eval`: ATE and RPE of an estimated trajectory against ground truth, as TUM's evaluate_ate.py and
// evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s (slam/eval.h), optionally with a plot (slam/eval_plot.h).
#include <CLI/CLI.hpp>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "apps/cli_common.h"
#include "apps/commands.h"
#include "core/error.h"
#include "io/trajectory_io.h"
#include "slam/eval.h"
#include "slam/eval_plot.h"

namespace hf::apps {
namespace {

struct EvalArgs {
  std::string gt_path, est_path, plot_path;
  bool json = false, per_frame = false;
  double max_difference_s = 0.02, offset_s = 0.0, delta_s = 1.0;
};

void run_eval(const EvalArgs& args) {
  const Trajectory gt = read_tum_trajectory(args.gt_path);
  const Trajectory est = read_tum_trajectory(args.est_path);
  EvalResult result;
  try {
    result = evaluate_trajectory(
        gt, est, {.max_difference_s = args.max_difference_s, .offset_s = args.offset_s, .rpe_delta_s = args.delta_s});
  } catch (const ParseError&) {
    throw;
  } catch (const Error& e) {
    throw Error(args.est_path + " vs " + args.gt_path + ": " + e.what());
  }
  const TrajectoryMetrics metrics = result.metrics();

  if (!args.plot_path.empty()) {
    TrajectoryPlotOptions plot;
    plot.title = args.est_path + " vs " + args.gt_path;
    write_trajectory_plot(args.plot_path, gt, est, result, plot);
  }
  if (args.json) {
    nlohmann::json j = metrics_to_json(metrics);
    j["ground_truth"] = args.gt_path;
    j["estimate"] = args.est_path;
    j["max_difference_s"] = args.max_difference_s;
    j["offset_s"] = args.offset_s;
    if (!args.plot_path.empty()) j["plot"] = args.plot_path;
    if (args.per_frame) j["per_frame"] = per_frame_to_json(result);
    std::cout << j.dump(2) << "\n";
    return;
  }
  std::cout << "ground truth: " << args.gt_path << " (" << gt.size() << " poses)\n"
            << "estimate:     " << args.est_path << " (" << est.size() << " poses)\n"
            << "associated:   " << metrics.pairs << " pairs within " << args.max_difference_s << " s; RPE over "
            << args.delta_s << " s: " << metrics.rpe_pairs << " pairs";
  if (result.rpe.rejected_gap_pairs > 0) {
    std::cout << " (" << result.rpe.rejected_gap_pairs << " rejected: ground truth more than "
              << result.rpe.gt_max_time_difference_s << " s away)";
  }
  std::cout << "\n\n" << format_metrics_table(metrics);
  if (args.per_frame) {
    std::cout << "\n# per pose ATE: gt_stamp est_stamp error_m\n";
    for (const AtePair& p : result.ate.pairs) {
      std::cout << std::fixed;
      std::cout.precision(6);
      std::cout << p.gt_stamp_s << ' ' << p.est_stamp_s << ' ' << p.error_m << "\n";
    }
    std::cout << "# per pair RPE: est_stamp_0 est_stamp_1 gt_stamp_0 gt_stamp_1 trans_m_per_s rot_deg_per_s\n";
    for (const RpePair& p : result.rpe.pairs) {
      std::cout << p.est_stamp_0_s << ' ' << p.est_stamp_1_s << ' ' << p.gt_stamp_0_s << ' ' << p.gt_stamp_1_s << ' '
                << p.trans_m_per_s << ' ' << p.rot_deg_per_s << "\n";
    }
    std::cout.unsetf(std::ios::floatfield);
  }
  if (!args.plot_path.empty()) std::cout << "\nplot written to " << args.plot_path << "\n";
}

}  // namespace

void add_eval_command(CLI::App& app) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "ATE (evaluate_ate.py: association, Horn alignment without scale) and RPE per second (evaluate_rpe.py "
      "--fixed_delta --delta 1 --delta_unit s) of an estimated TUM trajectory against ground truth");
  cmd->add_option("--gt", args->gt_path, "ground-truth trajectory, TUM format (timestamp tx ty tz qx qy qz qw)")
      ->required();
  cmd->add_option("--est", args->est_path, "estimated trajectory, TUM format")->required();
  cmd->add_option("--plot", args->plot_path,
                  "write a PNG of the ground truth and the aligned estimate coloured by ATE error");
  cmd->add_flag("--json", args->json, "print one JSON object instead of the table");
  cmd->add_flag("--per-frame", args->per_frame, "also print the per-pose ATE and per-pair RPE values");
  auto* max_difference = cmd->add_option("--max-difference-s", args->max_difference_s,
                                         "largest time difference (s) for associating a ground-truth and an "
                                         "estimated pose")
                              ->check(in_range(0.0, 1e6, "s"))
                              ->capture_default_str();
  add_deprecated_alias(cmd, max_difference, "--max-difference", args->max_difference_s)->check(in_range(0.0, 1e6));
  auto* offset = cmd->add_option("--offset-s", args->offset_s, "time offset (s) added to the estimate's timestamps")
                     ->check(in_range(-1e9, 1e9, "s"))
                     ->capture_default_str();
  add_deprecated_alias(cmd, offset, "--offset", args->offset_s)->check(in_range(-1e9, 1e9));
  auto* delta = cmd->add_option("--delta-s", args->delta_s,
                                "RPE pose distance in seconds (errors are reported per second)")
                    ->check(in_range(1e-6, 1e6, "s"))
                    ->capture_default_str();
  add_deprecated_alias(cmd, delta, "--delta", args->delta_s)->check(in_range(1e-6, 1e6));
  cmd->callback([args] { run_eval(*args); });
}

}  // namespace hf::apps
