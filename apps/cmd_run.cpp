// `hashfusion run`: the main job. Until fusion and registration land, it replays a dataset with a trivial pose
// source ("groundtruth" or "identity"), then evaluates and reports the trajectory, so the whole path from input
// to report is exercised and every output a user expects is already in place.
#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>

#include "apps/commands.h"
#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "core/timing.h"
#include "datasets/synthetic_source.h"
#include "io/dataset.h"
#include "io/trajectory_io.h"
#include "slam/eval.h"
#include "slam/eval_plot.h"

namespace hf::apps {
namespace {

std::atomic<bool> g_interrupted{false};
extern "C" void on_sigint(int) { g_interrupted.store(true); }

struct RunOptions {
  std::string input = "synthetic:room";
  std::string out = "out/run";
  std::string registration = "groundtruth";
  std::string camera;
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

void run(const RunOptions& o) {
  if (o.registration != "groundtruth" && o.registration != "identity")
    throw Error("unknown --registration '" + o.registration + "' (known now: groundtruth, identity)");
  std::unique_ptr<FrameSource> source = open_input(o);
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec || !std::filesystem::is_directory(o.out)) throw Error(o.out + ": cannot create output folder");

  std::cerr << "input: " << source->name() << ", " << source->size() << " frames\n"
            << "camera: " << source->camera().describe() << " (" << source->camera_origin() << ")\n";

  const long total = o.max_frames > 0 ? std::min<long>(o.max_frames, long(source->size())) : long(source->size());
  Trajectory estimate;
  StageTimes times;
  long frames = 0, bad = 0, lost = 0;
  std::optional<SE3> first_pose;
  auto previous = std::signal(SIGINT, on_sigint);
  {
    Progress progress("run", total);
    while (frames + bad < total && !g_interrupted.load()) {
      FrameRead r;
      {
        ScopedTimer t(times, "read");
        r = source->next();
      }
      if (r.status == FrameStatus::end) break;
      if (r.status == FrameStatus::bad_frame) {
        ++bad;
        std::cerr << "\nwarning: skipping frame " << r.frame.index << ": " << r.message << "\n";
        continue;
      }
      ++frames;
      ScopedTimer t(times, "track");
      std::optional<SE3> pose;
      if (o.registration == "groundtruth") {
        pose = r.frame.T_world_camera_gt;
      } else {
        if (!first_pose) first_pose = r.frame.T_world_camera_gt.value_or(SE3());
        pose = first_pose;
      }
      if (!pose) {
        ++lost;
      } else {
        estimate.push_back({r.frame.timestamp_s, *pose});
      }
      progress.update(frames + bad, lost ? "lost " + std::to_string(lost) : "good");
    }
    progress.finish();
  }
  std::signal(SIGINT, previous);
  if (g_interrupted.load()) std::cerr << "interrupted: writing outputs for the " << frames << " frames processed\n";
  if (frames == 0) throw Error(o.input + ": no usable frames");

  const std::string traj_path = o.out + "/trajectory.txt";
  write_tum_trajectory(traj_path, estimate, "hashfusion run --registration " + o.registration + "\ninput: " + o.input);

  nlohmann::json report;
  report["input"] = o.input;
  report["frames"] = frames;
  report["frames_bad"] = bad;
  report["frames_lost"] = lost;
  report["registration"] = o.registration;
  report["camera"] = source->camera().describe();
  report["camera_origin"] = source->camera_origin();
  const double total_ms = times.total_ms("read") + times.total_ms("track");
  report["fps"] = total_ms > 0 ? nlohmann::json(1000.0 * double(frames) / total_ms) : nlohmann::json(nullptr);
  report["ms_per_frame"] = {{"read", times.mean_ms("read")}, {"track", times.mean_ms("track")},
                            {"total", frames ? total_ms / double(frames) : 0.0}};
  std::vector<std::string> outputs = {traj_path};

  std::string metrics_md = "no ground truth: trajectory not evaluated\n";
  const Trajectory& gt = source->ground_truth();
  report["ate_rmse_m"] = nullptr;
  report["rpe_trans_m_per_s"] = nullptr;
  report["rpe_rot_deg_per_s"] = nullptr;
  if (!gt.empty() && estimate.size() >= kMinAtePairs) {
    const EvalResult eval = evaluate_trajectory(gt, estimate);
    const TrajectoryMetrics m = eval.metrics();
    report["metrics"] = metrics_to_json(m);
    report["ate_rmse_m"] = m.ate_m.rmse;
    if (m.rpe_trans_m_per_s) report["rpe_trans_m_per_s"] = m.rpe_trans_m_per_s->rmse;
    if (m.rpe_rot_deg_per_s) report["rpe_rot_deg_per_s"] = m.rpe_rot_deg_per_s->rmse;
    metrics_md = format_metrics_markdown(m);
    const std::string plot_path = o.out + "/trajectory.png";
    TrajectoryPlotOptions plot;
    plot.title = "hashfusion run: " + o.input + " (" + o.registration + ")";
    write_trajectory_plot(plot_path, gt, estimate, eval, plot);
    outputs.push_back(plot_path);
  }
  report["config"] = {{"input", o.input},       {"out", o.out},   {"registration", o.registration},
                      {"camera", o.camera},     {"max_frames", o.max_frames},
                      {"synthetic_frames", o.synthetic_frames}, {"seed", o.seed}};

  const std::string json_path = o.out + "/report.json";
  const std::string md_path = o.out + "/report.md";
  write_file_atomically(json_path, [&](std::ostream& out) { out << report.dump(2) << "\n"; });
  std::ostringstream md;
  md << "# hashfusion run\n\n"
     << "| | |\n|---|---|\n"
     << "| input | `" << o.input << "` (" << source->name() << ") |\n"
     << "| camera | " << source->camera().describe() << " (" << source->camera_origin() << ") |\n"
     << "| registration | " << o.registration << " |\n"
     << "| frames | " << frames << " used, " << bad << " bad, " << lost << " lost |\n"
     << "| ms per frame | read " << times.mean_ms("read") << ", track " << times.mean_ms("track") << " |\n\n"
     << "## Trajectory error\n\n" << metrics_md;
  write_file_atomically(md_path, [&](std::ostream& out) { out << md.str(); });
  outputs.push_back(json_path);
  outputs.push_back(md_path);

  std::cout << "outputs:\n";
  for (const auto& p : outputs) std::cout << "  " << std::filesystem::absolute(p).string() << "\n";
  if (report["ate_rmse_m"].is_number()) std::cout << "ATE RMSE: " << report["ate_rmse_m"].get<double>() << " m\n";
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto opts = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Replay a dataset, track, and write trajectory, report and plots");
  cmd->add_option("--input", opts->input, "synthetic:PRESET, a TUM RGB-D folder, or a 7-Scenes folder")
      ->capture_default_str();
  cmd->add_option("--out", opts->out, "output folder")->capture_default_str();
  cmd->add_option("--registration", opts->registration, "groundtruth | identity (more with the registration issue)")
      ->capture_default_str();
  cmd->add_option("--camera", opts->camera, "camera preset name or camera file (default: chosen per dataset)");
  cmd->add_option("--max-frames", opts->max_frames, "stop after N frames (0 = all)")->check(CLI::NonNegativeNumber);
  cmd->add_option("--synthetic-frames", opts->synthetic_frames, "frames of a synthetic: input")
      ->check(CLI::Range(1, 100000))
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "noise seed of a synthetic: input")->capture_default_str();
  cmd->callback([opts] { run(*opts); });
}

}  // namespace hf::apps
