// `hashfusion run`: the main job. A dataset (TUM or 7-Scenes folder, or synthetic:PRESET generated on the fly) goes
// through the SLAM pipeline (slam/pipeline.h) and the outputs land in --out: trajectory.txt, mesh.ply, report.json,
// report.md, render.png and, with ground truth, trajectory.png. --out is checked writable before the first frame.
// Ctrl-C, SIGTERM or SIGHUP stops after the current frame, writes every output for the frames processed and exits
// 130 / 143 / 129 (apps/interrupt.h); a full voxel block pool does the same and exits 1 naming the flag that raises it.
#include <CLI/CLI.hpp>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iostream>
#include <vector>
#include <set>

#include "apps/build_info.h"
#include "apps/cli_common.h"
#include "apps/commands.h"
#include "apps/interrupt.h"
#include "apps/registration_list.h"
#include "apps/invocation.h"
#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "core/output_transaction.h"
#include "datasets/synthetic_source.h"
#include "fusion/voxel_block_grid.h"
#include "fusion/volume_io.h"
#include "io/dataset.h"
#include "io/live_input.h"
#include "io/pcd.h"
#include "io/ply.h"
#include "io/replay_source.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"
#if HF_HAVE_VIEWER
#include "viewer/run_viewer.h"
#endif

namespace hf::apps {
namespace {

struct RunOptions {
  std::string input = "synthetic:room";
  std::string out;  // --out: out/run unless given (add_out_option)
  std::string registration = "combined";
  std::string backend = "cpu";
  std::string camera;
  std::string config_file;
  double voxel_m = 0.01;
  int tracking_level = -1;  // -1: the configuration's
  long max_frames = 0;  // 0 = all
  size_t capacity_blocks = 0;  // 0: the configuration's
  int synthetic_frames = 90;
  std::uint64_t seed = 0;
  bool global = false;  // --global: final pose-graph optimisation over all keyframes and re-fusion
  bool realtime = false;  // --realtime: a recording replayed at its recorded rate through the live queue
  std::string live_mode = "640x480@30";  // --live-mode for live inputs
  bool view = false;                     // --view: the viewer follows the run
  std::string screenshot;                // --screenshot FILE.png: headless viewer, final view
  long screenshot_every = 0;             // --screenshot-every N: headless, every N frames too
  std::string save_map;                  // --save-map [FILE]: "" none; a bare name lands in --out
  std::string load_map;                  // --load-map FILE: continue in this map
  std::string save_cloud;                // --save-cloud [FILE.ply|.pcd]
};

// The surface cloud as PLY or PCD by the extension (io/pcd.h goes through PCL, linked here, not in hf_slam).
void write_cloud_file(const std::string& path, const PointCloud& cloud) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext == ".ply") {
    write_ply(path, cloud);
  } else if (ext == ".pcd") {
    write_pcd(path, cloud);
  } else {
    throw Error(path + ": expected a point cloud file name ending in .ply or .pcd");
  }
}

// --save-map / --save-cloud FILE: where it goes, checked before the first frame (the file is written atomically with
// the other outputs at the end, where a missing folder or a wrong extension would cost the whole run). Returns a
// bare name (one of `bare_names`: into --out) or an absolute path (the user's, relative to where the command runs).
// A path into --out itself (`--out o --save-map o/map.hfmap`) is the bare name: --out is replaced as a whole at the
// end (core/output_transaction.h), so a file written there beside the transaction would be lost.
std::string resolve_extra_output(const std::string& option, const std::string& path, const std::string& out,
                                 const std::vector<std::string>& bare_names) {
  if (path.empty()) return path;
  std::filesystem::path p(path);
  if (!p.parent_path().empty() &&
      std::filesystem::absolute(p).lexically_normal().parent_path() == std::filesystem::absolute(out).lexically_normal())
    p = p.filename();
  if (p.parent_path().empty()) {
    if (std::find(bare_names.begin(), bare_names.end(), p.string()) == bare_names.end())
      throw Error(option + ": a bare file name must be " + bare_names.front() +
                  (bare_names.size() > 1 ? " or " + bare_names.back() : "") +
                  " (in --out); give a path for another place");
    return p.string();
  }
  if (option == "--save-cloud" && p.extension() != ".ply" && p.extension() != ".pcd")
    throw Error(option + ": " + path + ": expected a file name ending in .ply or .pcd");
  const std::string folder = p.parent_path().string();
  std::error_code ec;
  if (std::filesystem::is_directory(p, ec)) throw Error(option + ": " + path + " is a folder; give a file name");
  if (!std::filesystem::is_directory(folder, ec)) throw Error(option + ": " + path + ": no folder " + folder);
  if (access(folder.c_str(), W_OK | X_OK) != 0)
    throw Error(option + ": " + path + ": cannot write into " + folder + " (" + std::strerror(errno) + ")");
  return std::filesystem::absolute(p).string();
}

#if HF_HAVE_VIEWER
// The viewer hooks into the loop through RunControl::observe (slam/sequence_run.h): a snapshot copy per frame,
// the pause/step keys held there, 's' saving the mesh, and 'q' / a closed window ending the run as Ctrl-C does
// (outputs written) but with exit status 0.
struct RunView {
  std::unique_ptr<viewer::RunViewer> viewer;
  std::shared_ptr<std::atomic<bool>> stop = std::make_shared<std::atomic<bool>>(false);  // Ctrl-C or quit
};

RunView start_viewer(const RunOptions& o, const FrameSource& source, const slam::Pipeline& pipeline,
                     slam::RunControl& control, const std::atomic<bool>* interrupt) {
  RunView view;
  if (!o.view && o.screenshot.empty()) return view;
  viewer::RunViewerOptions v;
  v.window = o.view && o.screenshot.empty();
  v.screenshot = o.screenshot;
  v.screenshot_every = o.screenshot_every;
  v.out_dir = o.out;
  view.viewer = std::make_unique<viewer::RunViewer>(source.camera(), v);
  viewer::RunViewer* raw = view.viewer.get();
  auto saved = std::make_shared<int>(0);
  control.observe = [raw, &pipeline, saved, out = o.out, stop = view.stop, interrupt](const RgbdFrame& frame,
                                                                                       const slam::FrameResult& r) {
    raw->observe(frame, r, pipeline.map());
    if (raw->controller().take_save_request()) {
      const std::string path = out + "/mesh_view_" + std::to_string((*saved)++) + ".ply";
      write_ply(path, pipeline.extract_mesh());
      std::cerr << "\nviewer: saved " << path << "\n";
    }
    raw->hold(pipeline.map());
    if (raw->controller().quit_flag()->load() || interrupt->load()) stop->store(true);
  };
  control.stop = view.stop.get();
  return view;
}
#endif

std::unique_ptr<FrameSource> open_input(const RunOptions& o) {
  if (datasets::is_synthetic_input(o.input)) {
    datasets::SyntheticOptions s;
    s.frames = o.synthetic_frames;
    s.seed = o.seed;
    if (!o.camera.empty()) s.camera = camera_from_option(o.camera).camera;
    return datasets::open_synthetic_input(o.input, s);
  }
  if (is_live_input(o.input)) return open_live_input(o.input, live_input_options(o.live_mode, o.camera));
  DatasetOptions d;
  d.camera = o.camera;
  return open_dataset(o.input, d);
}

// --realtime: the recording through a camera's queue at its recorded rate (io/replay_source.h).
std::unique_ptr<FrameSource> open_run_input(const RunOptions& o) {
  std::unique_ptr<FrameSource> source = open_input(o);
  if (!o.realtime) return source;
  if (source->size() == kUnknownFrameCount) return source;  // live already
  return open_realtime_replay(std::move(source));
}

std::string frames_text(const FrameSource& source) {
  return source.size() == kUnknownFrameCount ? std::string("live") : std::to_string(source.size()) + " frames";
}

// The configuration: defaults, then the --config file, then the flags given on the command line.
slam::PipelineConfig make_config(const RunOptions& o, const CLI::App& cmd) {
  slam::PipelineConfig c = o.config_file.empty() ? slam::PipelineConfig{} : slam::load_config(o.config_file);
  if (o.config_file.empty() || cmd.count("--registration")) c.registration = o.registration;
  if (o.config_file.empty() || cmd.count("--backend")) c.backend = o.backend;
  if (o.config_file.empty() || cmd.count("--voxel-m")) c.volume.voxel_m = o.voxel_m;
  if (o.tracking_level >= 0) c.tracking_level = o.tracking_level;
  if (o.capacity_blocks > 0) c.volume.capacity_blocks = o.capacity_blocks;
  // A method change on the command line keeps the file's driver settings (shared by every method) and takes the
  // new method's own knobs from their pipeline defaults.
  if (cmd.count("--registration") && c.registration_options && !o.config_file.empty() &&
      c.registration != "groundtruth") {
    RegistrationOptions fresh = slam::pipeline_registration_options(c.registration);
    fresh.driver = c.registration_options->driver;
    c.registration_options = fresh;
  }
  c.validate();
  return c;
}

// The pool grows on demand, so a capacity beyond the machine's memory would only fail deep into the run.
void check_capacity_fits_memory(const slam::PipelineConfig& c) {
  const double need = double(c.volume.capacity_blocks) * double(sizeof(fusion::VoxelBlock));
  const double have = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGESIZE));
  if (have > 0 && need > have)
    throw Error("capacity of " + std::to_string(c.volume.capacity_blocks) + " voxel blocks needs " +
                std::to_string(long(need / (1 << 20))) + " MiB, more than this machine's " +
                std::to_string(long(have / (1 << 20))) + " MiB of memory (lower --capacity-blocks)");
}

// The files the run that last wrote `out` listed in its report.json ("outputs"); those of a folder without a run's
// report.json (a user's folder, a foreign report) are none, so every file there is carried over.
std::function<bool(const std::string&)> previous_run_wrote(const std::string& out) {
  std::set<std::string> names;
  nlohmann::json j;
  if (read_previous_manifest(out + "/report.json", &j) && j.is_object() && j.contains("outputs") &&
      j["outputs"].is_array() && j.contains("config"))
    for (const nlohmann::json& name : j["outputs"])
      if (name.is_string() && std::count(slam::run_output_names().begin(), slam::run_output_names().end(),
                                         name.get<std::string>()) > 0)
        names.insert(name.get<std::string>());  // only names a run writes: a report cannot get notes.txt removed
  return [names](const std::string& name) { return names.count(name) > 0; };
}

void run(const RunOptions& o, const CLI::App& cmd) {
  const slam::PipelineConfig config = make_config(o, cmd);
  check_capacity_fits_memory(config);
  // Before the first frame, not after the last: the lock, and a private folder the outputs are built in and that
  // replaces --out in one step at the end (core/output_transaction.h).
  OutputTransaction outputs(o.out);
  InterruptGuard guard;  // from here on Ctrl-C / SIGTERM end the loop and the outputs are still written
  std::unique_ptr<FrameSource> source = open_run_input(o);
  if (source->size() == 0) throw Error(o.input + ": the dataset has no frames");
  std::cerr << "input: " << source->name() << ", " << frames_text(*source) << "\n"
            << "camera: " << source->camera().describe() << " (" << source->camera_origin() << ")\n"
            << "registration: " << config.registration << " (backend " << config.backend << "), voxel "
            << config.volume.voxel_m * 1000.0 << " mm\n";
  slam::Pipeline pipeline(config, source->camera());
  if (!o.load_map.empty()) {
    fusion::Volume map = fusion::load_volume(o.load_map);
    try {
      pipeline.load_map(std::move(map.grid), std::move(map.store));
    } catch (const Error& e) {
      throw Error(o.load_map + ": " + e.what());
    }
    std::cerr << "map: continuing in " << o.load_map << " (" << pipeline.map().block_count() << " blocks)\n";
  }

  slam::RunControl control;
  control.max_frames = o.max_frames;
  control.stop = guard.flag();
  control.progress_label = "run";
  control.global = o.global;
  // Live input and --realtime: the back-end's results land when they are ready (slam/pipeline.h set_realtime).
  control.realtime = o.realtime || source->size() == kUnknownFrameCount;
#if HF_HAVE_VIEWER
  RunOptions staged = o;
  staged.out = outputs.folder();  // the viewer's saved meshes are outputs of this run too
  RunView view = start_viewer(staged, *source, pipeline, control, guard.flag());
#else
  if (o.view || !o.screenshot.empty())
    throw Error("--view / --screenshot: the viewer is not built in (install libglfw3-dev and libglm-dev, reconfigure)");
#endif
  const slam::SequenceRun result = slam::run_sequence(*source, pipeline, control);
  if (result.frames.empty()) {
    guard.exit_if_interrupted("before the first frame, nothing written");
    if (!result.stopped_by.empty()) throw Error(o.input + ": " + result.stopped_by);
    throw Error(o.input + ": no usable frames");
  }
  if (result.interrupted)
    std::cerr << "interrupted: writing outputs for the " << result.frames.size() << " frames processed\n";
  if (!result.stopped_by.empty())
    std::cerr << "stopped early (" << result.stopped_by << "): writing outputs for the " << result.frames.size()
              << " frames processed\n";

  if (!result.input_ended.empty())
    std::cerr << "input ended: " << result.input_ended << ": writing outputs for the " << result.frames.size()
              << " frames processed\n";
  slam::RunSummary summary = slam::summarize(result, pipeline, *source, o.input);
  summary.version = build_version();
  summary.commit = build_commit();
  summary.command_line = invocation_command_line();
  summary.started_utc = invocation_started_utc();
  slam::RunOutputOptions extra;
  extra.map = o.save_map;
  extra.cloud = o.save_cloud;
  extra.write_cloud = write_cloud_file;
  const std::vector<std::string> written =
      slam::write_run_outputs(outputs.folder(), result, summary, pipeline, *source, extra);
  outputs.commit(previous_run_wrote(outputs.target()));
  std::cout << "outputs:\n";
  for (const auto& p : written)
    std::cout << "  " << (std::filesystem::path(outputs.target()) / std::filesystem::path(p).filename()).string()
              << "\n";
  std::cout << "frames: " << summary.frames << " (" << summary.frames_lost << " lost, " << summary.frames_bad
            << " unreadable), " << summary.fps << " fps\n";
  if (summary.capture) {
    std::cout << "capture: " << summary.capture->captured << " frames at " << summary.capture->input_fps
              << " fps, processed " << summary.capture->delivered << " at " << summary.capture->delivered_fps
              << " fps, dropped " << summary.capture->dropped << "\n";
    if (summary.latency_p50_ms)
      std::cout << "latency (arrival to pose): p50 " << *summary.latency_p50_ms << " ms, p95 "
                << *summary.latency_p95_ms << " ms, max " << *summary.latency_max_ms << " ms\n";
  }
  if (const auto ate = summary.ate_rmse_m()) {
    std::cout << "ATE RMSE: " << *ate << " m" << (o.global ? " (after --global)" : "");
    if (summary.ate_online_m) std::cout << ", online " << *summary.ate_online_m << " m";
    std::cout << "\n";
  }
#if HF_HAVE_VIEWER
  if (view.viewer) {
    if (o.screenshot.empty()) std::cerr << "viewer: showing the final mesh; close the window to exit\n";
    view.viewer->finish(pipeline.extract_mesh(), pipeline.last_good_pose().value_or(SE3()));
    if (!o.screenshot.empty()) std::cout << "screenshot: " << std::filesystem::absolute(o.screenshot).string() << "\n";
  }
#endif
  const bool live = source->size() == kUnknownFrameCount;
  const std::string done = "outputs written for " + std::to_string(summary.frames) +
                           (live ? std::string(" frames (live)") : " of " + frames_text(*source));
  guard.exit_if_interrupted(done);
  if (!result.stopped_by.empty())
    throw Error(o.input + ": " + done + "; stopped at " + result.stopped_by + " (now --capacity-blocks " +
                std::to_string(config.volume.capacity_blocks) + ")");
}

}  // namespace

void add_run_command(CLI::App& app) {
  auto opts = std::make_shared<RunOptions>();
  CLI::App* cmd = app.add_subcommand("run", "Track and fuse a dataset; write trajectory, mesh, report and plots");
  cmd->add_option("--input", opts->input,
                  "synthetic:PRESET, a TUM RGB-D folder, a 7-Scenes folder, or live: openni2://[URI], FILE.oni, "
                  "v4l2:///dev/videoN[+/dev/videoM], libcamera://[ID] (`hashfusion devices` lists them)")
      ->capture_default_str();
  add_out_option(cmd, opts->out, "output folder");
  cmd->add_option("--registration", opts->registration, "registration method: " + registration_list() + ", or groundtruth (fusion only)")
      ->capture_default_str();
  cmd->add_option("--backend", opts->backend, "reduction backend: cpu | opencl")->capture_default_str();
  cmd->add_option("--voxel-m", opts->voxel_m, "voxel size in metres")->check(voxel_m_range())
      ->capture_default_str();
  cmd->add_option("--tracking-level", opts->tracking_level,
                  "pyramid level tracking starts at (0 full, 1 half, 2 quarter resolution); default: the configuration's")
      ->check(tracking_level_range());
  cmd->add_option("--camera", opts->camera, "camera preset name or camera file (default: chosen per dataset)");
  cmd->add_flag("--view", opts->view, "a window follows the run (model, trajectory, input; space pause, n step, "
               "r reset view, s save mesh, q quit; drag to orbit, scroll to zoom)");
  cmd->add_option("--screenshot", opts->screenshot,
                  "headless viewer: write the final mesh's OpenGL view from the last pose to FILE.png");
  cmd->add_option("--screenshot-every", opts->screenshot_every,
                  "with --screenshot: also FILE_NNNNNN.png of the model so far every N frames")
      ->check(positive());
  cmd->add_option("--live-mode", opts->live_mode, "live inputs: WIDTHxHEIGHT@FPS to ask the device for")
      ->capture_default_str();
  cmd->add_flag("--realtime", opts->realtime,
                "replay a recording at its recorded rate (7-Scenes: 30 Hz) through a camera's queue of two frames, "
                "dropping the oldest when processing is slower: fps, dropped frames and latency as a live user "
                "would get them (the results then depend on timing)");
  cmd->add_flag("--global", opts->global,
               "after the last frame: optimise the keyframe pose graph once more and fuse the map anew from the "
               "corrected poses (report.json holds the online and the final trajectory's ATE)");
  cmd->add_option("--config", opts->config_file, "JSON pipeline configuration (report.json's \"config\" form)");
  cmd->add_option("--capacity-blocks", opts->capacity_blocks,
                  "voxel block pool size, 4 KiB per block (default: the configuration's, 131072 = 512 MiB)")
      ->check(in_range(1, double(size_t(1) << 26), "blocks"));
  cmd->add_option("--max-frames", opts->max_frames, "stop after N frames (0 = all)")->check(non_negative());
  cmd->add_option("--synthetic-frames", opts->synthetic_frames, "frames of a synthetic: input")
      ->check(synthetic_frames_range())
      ->capture_default_str();
  cmd->add_option("--seed", opts->seed, "noise seed of a synthetic: input")->check(seed_range())->capture_default_str();
  cmd->add_option("--save-map", opts->save_map,
                  "also write the map (the TSDF volume, fusion/volume_io.h; no keyframes) to FILE, by default "
                  "map.hfmap in --out; written with the other outputs, also after Ctrl-C / SIGTERM")
      ->expected(0, 1)
      ->default_str("map.hfmap");
  cmd->add_option("--load-map", opts->load_map,
                  "continue in a saved map: the first frame is placed at its ground-truth pose, else at the map's "
                  "origin (the first camera of the session that built it); voxel size as the map's");
  cmd->add_option("--save-cloud", opts->save_cloud,
                  "also write the surface as a point cloud with colour and normals, FILE.ply or FILE.pcd, by "
                  "default cloud.ply in --out")
      ->expected(0, 1)
      ->default_str("cloud.ply");
  cmd->callback([opts, cmd] {
    // A flag given without a value takes its default name in --out (CLI11 leaves the value empty then).
    if (cmd->count("--save-map") && opts->save_map.empty()) opts->save_map = "map.hfmap";
    if (cmd->count("--save-cloud") && opts->save_cloud.empty()) opts->save_cloud = "cloud.ply";
    opts->save_map = resolve_extra_output("--save-map", opts->save_map, opts->out, {"map.hfmap"});
    opts->save_cloud = resolve_extra_output("--save-cloud", opts->save_cloud, opts->out, {"cloud.ply", "cloud.pcd"});
    run(*opts, *cmd);
  });
}

}  // namespace hf::apps
