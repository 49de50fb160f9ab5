// run_bench: the part of the harness that drives slam::Pipeline.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <nlohmann/json.hpp>

#include "bench/harness/frame_rpe.h"
#include "bench/harness/harness.h"
#include "bench/harness/inputs.h"
#include "bench/harness/speed_plot.h"
#include "core/error.h"
#include "core/progress.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/synthetic_source.h"
#include "datasets/tum_writer.h"
#include "io/dataset.h"
#include "io/trajectory_io.h"
#include "slam/eval.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"

namespace hf::bench {
namespace fs = std::filesystem;
namespace {

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

std::string one_line(std::string s) {
  for (char& ch : s) {
    if (ch == '\n' || ch == '\r') ch = ' ';
  }
  return s;
}

std::string describe(const RunRow& r) {
  if (r.failed) return "failed: " + r.error;
  char buffer[256];
  std::snprintf(buffer, sizeof buffer, "ATE %s, %ld/%ld frames lost, %.1f ms per frame (%.1f fps)%s",
                r.ate_rmse_m ? (std::to_string(*r.ate_rmse_m) + " m").c_str() : "n/a", r.frames_lost, r.frames,
                r.ms.total, r.fps, r.interrupted ? ", interrupted" : "");
  return buffer;
}

// The per-frame-pair RPE (frame_rpe.h) of a run that has an ATE (the same ground truth the ATE used).
void set_frame_rpe(RunRow& row, const Trajectory& gt, const Trajectory& estimate) {
  if (!row.ate_rmse_m || gt.empty()) return;
  const FrameRpe rpe = evaluate_rpe_per_frame(gt, estimate);
  if (rpe.empty()) return;
  row.rpe_frame_trans_m = rpe.trans_m.rmse;
  row.rpe_frame_rot_deg = rpe.rot_deg.rmse;
}

// The input's frames as a FrameSource, with --camera where given; synthetic inputs read their rendered TUM folder.
std::unique_ptr<FrameSource> open_input(const std::string& folder, const BenchOptions& o) {
  DatasetOptions d;
  d.camera = o.camera;
  return open_dataset(folder, d);
}

// What the tables show as the source: the dataset reader's name, or the preset for a rendered synthetic input
// (whose temporary folder means nothing to a reader), and the camera the frames were read with.
std::string source_name(const BenchInput& input, const FrameSource& source) {
  const std::string camera = "; camera " + source.camera().describe();
  if (!input.synthetic) return source.name() + camera;
  return "synthetic preset '" + input.spec.substr(std::string(datasets::kSyntheticPrefix).size()) + "', " +
         std::to_string(source.size()) + " frames rendered (datasets/presets.h) and read back as a TUM folder" + camera;
}

RunRow run_method(const BenchInput& input, const std::string& folder, const std::string& method,
                  const std::string& loop_mode, const BenchOptions& o, Trajectory& estimate) {
  RunRow row;
  row.method = loop_closure_label(method, loop_mode);
  row.input = input.label;
  const auto start = std::chrono::steady_clock::now();
  try {
    std::unique_ptr<FrameSource> source = open_input(folder, o);
    row.source = source_name(input, *source);
    slam::PipelineConfig config = o.config_file.empty() ? slam::PipelineConfig{} : slam::load_config(o.config_file);
    // Each registration is measured as itself: the colour check (slam/colour_check.h), which hands a method that
    // reads colour over to icp where the colour is not registered to the depth, is off unless a --config asks.
    if (o.config_file.empty()) config.colour_check.enabled = false;
    if (config.registration != method) config.registration_options.reset();
    config.registration = method;
    config.backend = o.backend;
    config.volume.voxel_m = o.voxel_m;
    if (o.tracking_level >= 0) config.tracking_level = o.tracking_level;
    if (loop_mode == "off") config.loop_closure.enabled = false;
    slam::Pipeline pipeline(config, source->camera());
    slam::RunControl control;
    control.global = loop_mode == "global";
    control.max_frames = o.max_frames;
    control.stop = o.stop;
    if (o.progress) control.progress_label = input.label + " " + row.method;
    const slam::SequenceRun run = slam::run_sequence(*source, pipeline, control);
    const slam::RunSummary s = slam::summarize(run, pipeline, *source, input.spec);
    row.interrupted = s.interrupted;
    row.frames = s.frames;
    row.frames_bad = s.frames_bad;
    row.frames_lost = s.frames_lost;
    row.coverage = s.coverage;
    row.lost_spells = s.lost_spells;
    row.longest_lost_spell = s.longest_lost_spell;
    row.worst_frame_ms = s.worst_frame_ms;
    row.ate_rmse_m = s.ate_rmse_m();
    row.rpe_trans_m_per_s = s.rpe_trans_m_per_s();
    row.rpe_rot_deg_per_s = s.rpe_rot_deg_per_s();
    row.fps = s.fps;
    row.ms = {s.mean_ms.read, s.mean_ms.preprocess, s.mean_ms.track, s.mean_ms.integrate, s.mean_ms.raycast,
              s.mean_ms.total()};
    estimate = run.estimate();
    set_frame_rpe(row, source->ground_truth(), estimate);
  } catch (const std::exception& e) {  // hf::Error, fusion::CapacityError, std::bad_alloc: a failed row
    row.failed = true;
    row.error = one_line(e.what());
  }
  row.wall_s = seconds_since(start);
  return row;
}

RunRow run_peer_row(const BenchInput& input, const std::string& folder, const std::string& peer,
                    const BenchOptions& o, Trajectory& estimate) {
  RunRow row;
  row.method = peer;
  row.peer = true;
  row.input = input.label;
  const auto start = std::chrono::steady_clock::now();
  try {
    std::unique_ptr<FrameSource> source = open_input(folder, o);
    row.source = source_name(input, *source);
    const PeerRun run = run_peer(*source, peer, o.peer, o.max_frames, o.stop,
                                 o.progress ? input.label + " " + peer + " (peer)" : "");
    row.interrupted = run.interrupted;
    row.frames = long(run.frames.size());
    row.frames_bad = run.frames_bad;
    row.frames_lost = run.frames_lost();
    double sum_read = 0, sum_pre = 0, sum_track = 0;
    long spell = 0;
    for (const PeerFrame& f : run.frames) {
      sum_read += f.ms_read, sum_pre += f.ms_preprocess, sum_track += f.ms_track;
      row.worst_frame_ms = std::max(row.worst_frame_ms, f.ms_read + f.ms_preprocess + f.ms_track);
      spell = f.pose_valid ? 0 : spell + 1;
      row.lost_spells += spell == 1;
      row.longest_lost_spell = std::max(row.longest_lost_spell, spell);
    }
    row.coverage = run.frames.empty() ? 0.0 : 1.0 - double(row.frames_lost) / double(run.frames.size());
    const double n = std::max<double>(1.0, double(run.frames.size()));
    row.ms = {sum_read / n, sum_pre / n, sum_track / n, 0.0, 0.0, (sum_read + sum_pre + sum_track) / n};
    const double total_ms = sum_read + sum_pre + sum_track;
    row.fps = total_ms > 0.0 ? 1000.0 * double(run.frames.size()) / total_ms : 0.0;
    estimate = run.estimate();
    const Trajectory& gt = source->ground_truth();
    if (!gt.empty() && estimate.size() >= kMinAtePairs) {
      try {
        const TrajectoryMetrics m = evaluate_trajectory(gt, estimate).metrics();
        row.ate_rmse_m = m.ate_m.rmse;
        if (m.rpe_trans_m_per_s) row.rpe_trans_m_per_s = m.rpe_trans_m_per_s->rmse;
        if (m.rpe_rot_deg_per_s) row.rpe_rot_deg_per_s = m.rpe_rot_deg_per_s->rmse;
        set_frame_rpe(row, gt, estimate);
      } catch (const Error&) {
        // No associated pairs (e.g. time stamps beyond the ground truth): no ATE, as for a pipeline run.
      }
    }
  } catch (const std::exception& e) {
    row.failed = true;
    row.error = one_line(e.what());
  }
  row.wall_s = seconds_since(start);
  return row;
}

// Renders `input` (synthetic:PRESET) into a TUM folder under `cache_root`; returns the folder.
std::string render_synthetic(const BenchInput& input, const std::string& cache_root, const BenchOptions& o) {
  datasets::SyntheticOptions s;
  s.preset = input.spec.substr(std::string(datasets::kSyntheticPrefix).size());
  s.frames = o.max_frames > 0 ? int(std::min<long>(o.max_frames, o.synthetic_frames)) : o.synthetic_frames;
  s.seed = o.seed;
  if (!o.camera.empty()) s.camera = camera_from_option(o.camera).camera;
  const datasets::SyntheticSequence sequence(s);
  const std::string dir = cache_root + "/" + file_safe(s.preset);
  datasets::TumWriteOptions w;
  w.overwrite = true;
  std::unique_ptr<Progress> progress;
  if (o.progress) {
    progress = std::make_unique<Progress>("render " + input.label, s.frames);
    w.progress = [&](int done, int) { progress->update(done); };
  }
  datasets::write_tum_folder(sequence, dir, w);
  if (progress) progress->finish();
  return dir;
}

std::string settings_line(const BenchOptions& o) {
  const std::string camera = o.camera.empty() ? "per dataset" : "'" + o.camera + "'";
  std::vector<char> buffer(512 + camera.size());  // a camera file's path has no bound
  std::snprintf(buffer.data(), buffer.size(),
                "voxel %.4g m, backend %s, max frames %s, camera %s, synthetic presets rendered with %d frames (%s "
                "camera, sensor noise on, seed %llu), peers voxel grid %.3g m, NDT cells %.3g m, pixel stride %d",
                o.voxel_m, o.backend.c_str(), o.max_frames > 0 ? std::to_string(o.max_frames).c_str() : "all",
                camera.c_str(),
                o.max_frames > 0 ? int(std::min<long>(o.max_frames, o.synthetic_frames)) : o.synthetic_frames,
                o.camera.empty() ? "640x480 'ros'" : "that",
                static_cast<unsigned long long>(o.seed), double(o.peer.voxel_m), double(o.peer.ndt_resolution_m), o.peer.pixel_stride);
  return buffer.data();
}

// The speed-vs-error plots (overall and per input) of `results` into `out`; returns their file names.
std::vector<std::string> write_plots(const std::string& out, const BenchResults& results) {
  std::vector<std::string> plot_files;
  {
    std::vector<SpeedPoint> points;
    SpeedPlotOptions plot;
    plot.title = "speed against error: all inputs (" + std::to_string(results.inputs.size()) + ")";
    plot.subtitle = "mean ms per frame over finished runs vs mean ATE RMSE over the inputs each method tracked";
    for (const MethodSummary& s : summarize_methods(results.runs, results.methods)) {
      if (s.mean_ate_m && s.mean_ms_per_frame) {
        points.push_back({s.name + " (" + std::to_string(s.inputs_comparable) + "/" + std::to_string(s.inputs_run) +
                              ")",
                          *s.mean_ms_per_frame, *s.mean_ate_m, s.peer});
      } else {
        plot.not_plotted.push_back(s.name);
      }
    }
    write_speed_plot(out + "/speed_vs_error.png", points, plot);
    plot_files.push_back("speed_vs_error.png");
  }
  for (const std::string& label : results.inputs) {
    std::vector<SpeedPoint> points;
    SpeedPlotOptions plot;
    plot.title = "speed against error: " + label;
    plot.subtitle = "ms per frame (all stages) vs ATE RMSE";
    bool any = false;
    for (const RunRow& r : results.runs) {
      if (r.input != label) continue;
      any = true;
      if (r.comparable()) {
        points.push_back({r.display_name(), r.ms.total, *r.ate_rmse_m, r.peer});
      } else {
        plot.not_plotted.push_back(r.display_name());
      }
    }
    if (!any) continue;
    const std::string name = "speed_vs_error_" + file_safe(label) + ".png";
    write_speed_plot(out + "/" + name, points, plot);
    plot_files.push_back(name);
  }

  return plot_files;
}

}  // namespace

BenchReport run_bench(const BenchOptions& o) {
  if (o.inputs.empty()) throw Error("bench: no --input given");
  if (o.registrations.empty() && o.peers.empty()) throw Error("bench: nothing to run (no registration, no peer)");
  if (o.synthetic_frames < 2) throw Error("bench: --synthetic-frames must be at least 2");
  if (!(o.voxel_m > 0.0)) throw Error("bench: --voxel-m must be positive");
  if (o.loop_closure_modes.empty()) throw Error("bench: no loop-closure mode");
  o.peer.validate();
  {
    // Fail fast on settings every run would reject.
    slam::PipelineConfig check = o.config_file.empty() ? slam::PipelineConfig{} : slam::load_config(o.config_file);
    if (o.tracking_level >= 0) check.tracking_level = o.tracking_level;
    check.backend = o.backend;
    check.volume.voxel_m = o.voxel_m;
    check.validate();
    if (!o.camera.empty()) camera_from_option(o.camera);  // an unknown preset or a malformed file: one line, now
  }
  const DiscoveredInputs discovered = discover_inputs(o.inputs);
  // The slice of the runs this process makes (--shard K/N; everything by default): run number `unit` counts the
  // (input, method) pairs in plan_runs() order, and a slice keeps only its inputs and methods in the tables.
  const size_t methods_per_input = o.registrations.size() * o.loop_closure_modes.size() + o.peers.size();
  const size_t total_runs = discovered.inputs.size() * methods_per_input;
  if (o.shard_count < 1 || o.shard_index < 0 || o.shard_index >= o.shard_count)
    throw Error("bench: --shard " + std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count) +
                ": expected K/N with 0 <= K < N");
  if (size_t(o.shard_count) > total_runs)
    throw Error("bench: --shard " + std::to_string(o.shard_index) + "/" + std::to_string(o.shard_count) + ": only " +
                std::to_string(total_runs) + (total_runs == 1 ? " run" : " runs") +
                " to share (bench --list-runs lists them): use at most that many slices");
  const std::pair<size_t, size_t> slice = shard_range(total_runs, o.shard_index, o.shard_count);
  const size_t first_run = slice.first, last_run = slice.second;
  auto in_slice = [&](size_t unit) { return unit >= first_run && unit < last_run; };
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec || !fs::is_directory(o.out)) throw Error(o.out + ": cannot create the output folder");
  const std::string traj_dir = o.out + "/trajectories";
  fs::create_directories(traj_dir, ec);
  const std::string cache_root = o.out + "/synthetic_cache";

  BenchReport report;
  BenchResults& results = report.results;
  results.machine = current_machine(o.source_dir, o.command_line);
  results.settings = settings_line(o);
  results.notes = discovered.notes;
  std::vector<std::string> all_methods;  // the table labels of one input's runs, in run order
  for (const std::string& m : o.registrations)
    for (const std::string& mode : o.loop_closure_modes) all_methods.push_back(loop_closure_label(m, mode));
  for (const std::string& p : o.peers) all_methods.push_back(p + " (peer)");
  for (size_t j = 0; j < all_methods.size(); ++j) {
    bool any = false;
    for (size_t i = 0; i < discovered.inputs.size() && !any; ++i) any = in_slice(i * methods_per_input + j);
    if (any) results.methods.push_back(all_methods[j]);
  }
  if (o.shard_count > 1)
    std::cerr << "shard " << o.shard_index << "/" << o.shard_count << ": runs " << first_run << ".." << last_run - 1
              << " of " << total_runs << "\n";
  for (const std::string& note : discovered.notes) std::cerr << "note: " << note << "\n";

  std::vector<std::string> trajectory_files;
  const size_t n_inputs = discovered.inputs.size();
  for (size_t i = 0; i < n_inputs; ++i) {
    if (o.stop && o.stop->load()) break;
    const BenchInput& input = discovered.inputs[i];
    const size_t input_first = i * methods_per_input;
    if (last_run <= input_first || first_run >= input_first + methods_per_input) continue;  // not in this slice
    results.inputs.push_back(input.label);
    std::cerr << "input " << (i + 1) << "/" << n_inputs << ": " << input.label << "\n";
    std::string folder = input.spec;
    if (input.synthetic) {
      try {
        folder = render_synthetic(input, cache_root, o);
      } catch (const std::exception& e) {
        // Every run on this input fails the same way; record it rather than abort the whole benchmark.
        for (size_t j = 0; j < methods_per_input; ++j) {
          if (!in_slice(input_first + j)) continue;
          const std::string& m = all_methods[j];
          RunRow row;
          const bool peer = m.size() > 7 && m.compare(m.size() - 7, 7, " (peer)") == 0;
          row.method = peer ? m.substr(0, m.size() - 7) : m;
          row.peer = peer;
          row.input = input.label;
          row.failed = true;
          row.error = "cannot render the preset: " + one_line(e.what());
          results.runs.push_back(row);
        }
        continue;
      }
    }
    auto record = [&](RunRow row, const Trajectory& estimate) {
      std::cerr << "  " << row.display_name() << ": " << describe(row) << "\n";
      if (!row.failed && !estimate.empty()) {
        const std::string path = traj_dir + "/" + file_safe(input.label) + "__" + file_safe(row.method) +
                                 (row.peer ? "_peer" : "") + ".txt";
        try {
          write_tum_trajectory(path, estimate,
                               "hashfusion bench: " + row.display_name() + " on " + input.label + " (" + row.source +
                                   ")");
          trajectory_files.push_back(path);
        } catch (const Error& e) {
          std::cerr << "warning: " << e.what() << "\n";
        }
      }
      results.runs.push_back(std::move(row));
    };
    size_t unit = input_first;
    for (const std::string& method : o.registrations) {
      for (const std::string& mode : o.loop_closure_modes) {
        if (!in_slice(unit++)) continue;
        if (o.stop && o.stop->load()) break;
        Trajectory estimate;
        RunRow row = run_method(input, folder, method, mode, o, estimate);
        record(std::move(row), estimate);
      }
    }
    for (const std::string& peer : o.peers) {
      if (!in_slice(unit++)) continue;
      if (o.stop && o.stop->load()) break;
      Trajectory estimate;
      RunRow row = run_peer_row(input, folder, peer, o, estimate);
      record(std::move(row), estimate);
    }
    if (input.synthetic) fs::remove_all(folder, ec);
  }
  fs::remove(cache_root, ec);  // only when empty

  const std::vector<std::string> plot_files = write_plots(o.out, results);
  report.files = write_results(o.out, results, plot_files);
  for (const std::string& f : plot_files) report.files.push_back(o.out + "/" + f);
  report.files.insert(report.files.end(), trajectory_files.begin(), trajectory_files.end());
  return report;
}

BenchReport merge_bench(const std::vector<std::string>& dirs, const std::string& out, const std::string& source_dir,
                        const std::string& command_line) {
  if (dirs.empty()) throw Error("bench --merge: no result folder given");
  BenchReport report;
  BenchResults& merged = report.results;
  merged.machine = current_machine(source_dir, command_line);
  auto add_unique = [](std::vector<std::string>& list, const std::string& item) {
    if (std::find(list.begin(), list.end(), item) == list.end()) list.push_back(item);
  };
  std::vector<std::string> settings;
  for (const std::string& dir : dirs) {
    const std::string file = dir + "/results.json";
    std::ifstream in(file);
    if (!in) throw Error(file + ": cannot open (bench --merge reads the results.json of earlier runs)");
    nlohmann::json j;
    try {
      in >> j;
    } catch (const nlohmann::json::exception& e) {
      throw ParseError(file, 0, std::string("expected JSON: ") + e.what());
    }
    const BenchResults part = results_from_json(j, file);
    merged.notes.push_back("rows of " + file + ": commit " + part.machine.commit + ", " + part.machine.date_utc +
                           ", `" + part.machine.command_line + "`");
    add_unique(settings, part.settings);
    for (const std::string& n : part.notes) add_unique(merged.notes, n);
    for (const std::string& m : part.methods) add_unique(merged.methods, m);
    for (const std::string& i : part.inputs) add_unique(merged.inputs, i);
    for (const RunRow& row : part.runs) {
      // A later folder's row replaces an earlier one of the same method on the same input.
      auto same = std::find_if(merged.runs.begin(), merged.runs.end(), [&](const RunRow& r) {
        return r.display_name() == row.display_name() && r.input == row.input;
      });
      if (same != merged.runs.end()) {
        *same = row;
      } else {
        merged.runs.push_back(row);
      }
    }
  }
  // Table order: hashfusion methods first, then peers (as run_bench writes them).
  std::stable_partition(merged.methods.begin(), merged.methods.end(), [](const std::string& m) {
    return !(m.size() > 7 && m.compare(m.size() - 7, 7, " (peer)") == 0);
  });
  for (size_t k = 0; k < settings.size(); ++k) merged.settings += (k ? "; " : "") + settings[k];
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec || !fs::is_directory(out)) throw Error(out + ": cannot create the output folder");
  const std::vector<std::string> plot_files = write_plots(out, merged);
  report.files = write_results(out, merged, plot_files);
  for (const std::string& f : plot_files) report.files.push_back(out + "/" + f);
  return report;
}

}  // namespace hf::bench
