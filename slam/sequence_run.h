// Running the pipeline over a whole frame source, and the summary both `hashfusion run` and `hashfusion bench`
// report from.
//
//   SequenceRun run = run_sequence(*source, pipeline, control);
//   RunSummary s = summarize(run, pipeline, *source);     // ATE/RPE when the source has ground truth
//   write_run_outputs(dir, run, s, pipeline, *source);     // trajectory.txt, mesh.ply, report.*, *.png
//
// Unreadable frames (FrameStatus::bad_frame) are skipped with a one-line warning and counted; a frame the
// pipeline rejects is counted as lost. `stop` (e.g. set by a SIGINT handler) ends the loop after the current
// frame, and everything processed so far is still summarised and written.
#pragma once

#include <atomic>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "io/frame_source.h"
#include "io/mesh.h"
#include "io/trajectory_io.h"
#include "slam/eval.h"
#include "slam/pipeline.h"

namespace hf::slam {

struct RunControl {
  long max_frames = 0;                        // frames to read (ok and bad), 0 = all
  const std::atomic<bool>* stop = nullptr;    // checked before each frame
  std::string progress_label;                 // non-empty: a progress bar (core/progress.h) with fps and status
  bool warn_bad_frames = true;                // print "warning: skipping frame ..." lines to stderr
  std::function<void(const FrameResult&)> on_frame;  // called after each processed frame
  // Called after each processed frame with its input too (the viewer's hook, apps/cmd_run.cpp); on the loop's
  // thread, so it must only copy what it needs (it may block on purpose: a paused viewer holds the run).
  std::function<void(const RgbdFrame&, const FrameResult&)> observe;
  // After the last frame: Pipeline::finish(global): drain the re-fusion queue, or (global, `--global`) solve the
  // keyframe graph once more and fuse the map anew from the final poses.
  bool global = false;
  // The pipeline's realtime mode (Pipeline::set_realtime): for live input and replay at the recorded rate
  // (io/replay_source.h), whose results depend on timing anyway.
  bool realtime = false;
};

struct SequenceRun {
  std::vector<FrameResult> frames;        // processed (decoded) frames, in order; `read` ms filled in
  std::vector<std::string> bad_frames;    // one line per unreadable frame, naming the file
  bool interrupted = false;               // stopped by RunControl::stop
  // Non-empty when the loop ended early on a resource limit (the voxel block pool full, fusion::CapacityError):
  // the message; the frames before it are kept and are written like an interrupted run's.
  std::string stopped_by;
  // Non-empty when a live source ended on its own (device unplugged or silent): FrameRead::message of its end.
  std::string input_ended;
  double wall_s = 0.0;                    // the whole loop
  // Live sources: per processed frame, ms from its arrival in the capture queue to its pose (process() returned);
  // and the time stamps of the frames the queue dropped (CaptureStats::dropped_timestamps_s).
  std::vector<double> latency_ms;
  std::vector<double> dropped_timestamps_s;

  long frames_lost() const;
  // Per frame, its pose after every loop closure (and the final optimisation with `global`):
  // Pipeline::corrected_trajectory() when the run ended. Empty when the run recorded none.
  std::vector<SE3> corrected;
  double finish_ms = 0.0;                 // Pipeline::finish()
  // The pose the run reports for EVERY processed frame (a lost frame's is the last estimate), TUM time stamps:
  // the corrected pose where there is one, else the online one. What trajectory.txt holds and ATE is computed
  // over, so a lost frame is never left out of the error. A frame the live queue dropped is there too, at the pose
  // the system showed when it arrived: the last processed frame's before it.
  Trajectory estimate() const;
  Trajectory online_estimate() const;     // the same with each frame's online pose (FrameResult::T_world_camera)  // (frames lost before the first placed frame have none)
  Trajectory tracked_estimate() const;    // only the frames with pose_valid (for comparison)
};

SequenceRun run_sequence(FrameSource& source, Pipeline& pipeline, const RunControl& control = {});

// What a run is judged by. Trajectory errors are empty without ground truth or with fewer than kMinAtePairs poses.
struct RunSummary {
  // Provenance, set by the caller after summarize() (the CLI: apps/build_info.h, its argv, when it started);
  // report.json writes an empty one as null.
  std::string version, commit;  // of the program that ran
  std::string command_line;     // as typed, each argument shell-quoted where it needs it
  std::string started_utc;      // ISO 8601, "2026-12-06T22:37:36Z"
  std::string input;            // as given by the user (path or synthetic:PRESET)
  std::string source_name;      // FrameSource::name()
  std::string registration, backend;
  double voxel_m = 0.0;
  long frames = 0, frames_bad = 0, frames_lost = 0, frames_degenerate = 0, frames_poor = 0;
  long frames_odometry = 0, frames_relocalised = 0, frames_fallback = 0;  // see slam/pipeline.h TrackState
  // Frames on which seed_on_failure ran, and those its retry placed (FrameResult::seeded_on_failure, placed_by_seed).
  long frames_seeded_on_failure = 0, frames_placed_by_seed = 0;
  long frames_wide_basin = 0;  // frames tracked without a motion prior, with the wide basin (FrameResult::wide_basin)
  double coverage = 0.0;        // frames with a valid pose / frames
  long lost_spells = 0, longest_lost_spell = 0;  // runs of consecutive lost frames
  size_t keyframes = 0;
  double worst_frame_ms = 0.0;  // the slowest frame's stage total (read included)
  std::optional<double> ate_tracked_only_m;  // ATE RMSE over the frames with a valid pose only
  std::optional<double> ate_online_m;        // ATE RMSE of the online poses (before loop closures moved them)
  size_t loops_closed = 0;
  size_t frames_reintegrated = 0;
  double loop_worst_ms = 0.0;               // the slowest loop-closure stage of a frame (tracking thread)
  // The back-end (slam/backend.h): jobs applied, their own time on the back-end thread (mean, worst), and the
  // re-fusion backlog: the largest after any frame (FrameResult::refusion_backlog); finish() drains it to 0.
  size_t backend_jobs = 0;
  double backend_job_mean_ms = 0.0, backend_job_worst_ms = 0.0;
  size_t refusion_backlog_max = 0;
  // Per-frame cost over the session (stage totals, read included): p95, and the means of the first and the last
  // quarter of the frames (a cost that grows with the session shows as last > first).
  double p95_frame_ms = 0.0, first_quarter_ms = 0.0, last_quarter_ms = 0.0;
  double finish_ms = 0.0;
  bool interrupted = false;
  std::optional<CaptureStats> capture;       // live sources: frames in / processed / dropped and both rates
  bool realtime = false;                     // Pipeline::realtime(): results depend on timing
  // Live sources: arrival-to-pose latency over the processed frames (SequenceRun::latency_ms).
  std::optional<double> latency_p50_ms, latency_p95_ms, latency_max_ms;
  std::optional<TrajectoryMetrics> metrics;  // ATE and RPE (1 s delta)
  // The colour check (slam/colour_check.h): its verdict, the median colour-to-depth scale of the window that
  // decided it, the frame it fell at, and the method that tracked at the end (colour_check.depth_only_registration
  // after an "unregistered" verdict, else `registration`).
  std::string colour_verdict = "undecided";
  double colour_median_scale = 1.0;
  std::optional<size_t> colour_decided_at_frame;
  std::string tracking_registration;
  double fps = 0.0;             // frames / sum of per-frame stage times
  StageMs mean_ms;              // per stage, averaged over processed frames (total = their sum)
  size_t blocks_allocated = 0;  // resident + streamed-out blocks at the end
  double bytes_per_voxel = 0.0;
  size_t memory_bytes = 0;      // the grid's memory (pool + hash)

  std::optional<double> ate_rmse_m() const;
  std::optional<double> rpe_trans_m_per_s() const;
  std::optional<double> rpe_rot_deg_per_s() const;
};

RunSummary summarize(const SequenceRun& run, const Pipeline& pipeline, const FrameSource& source,
                     const std::string& input);

// report.json (every field: docs/report.md): the fields of RunSummary (null where absent), "camera" as an object
// {fx, fy, cx, cy, width, height} (before issue 36 a string, PinholeCamera::describe(), which readers still
// accept), "stopped_by" (SequenceRun::stopped_by, null when the
// loop ran to its end or was interrupted), "input_ended" and "capture" (live sources; null otherwise), "ms_per_frame" {read, preprocess, track, integrate, raycast, total},
// "config" (config_to_json), per-frame states, and the camera; write_run_outputs adds "outputs".
nlohmann::json summary_to_json(const RunSummary& summary, const SequenceRun& run, const Pipeline& pipeline,
                               const FrameSource& source);

// Writes into `dir` (created if needed), each file atomically: trajectory.txt, mesh.ply (binary, coloured),
// report.json, report.md, render.png (the model from the last good pose, shaded in its fused colours) and
// trajectory.png (with ground truth). report.json's "outputs" lists the file names of this set; a file of ours
// (run_output_names()) that this run does not write, left by an earlier run into the same folder, is removed.
// Returns the paths written, in that order.
// Every file name write_run_outputs may write into its folder (map.hfmap, cloud.ply and cloud.pcd with
// RunOutputOptions naming them there).
const std::vector<std::string>& run_output_names();

// What a run writes besides the fixed set (`run --save-map`, `--save-cloud`): each a path, absolute or relative to
// the output folder; "" = not written. The map is fusion/volume_io.h's format (the TSDF's resident and streamed-out
// blocks; no keyframes, no trajectory); the cloud is the extracted surface's vertices with colour and normals, PLY
// or PCD by the extension.
struct RunOutputOptions {
  std::string map;    // e.g. "map.hfmap"
  std::string cloud;  // e.g. "cloud.ply" / "cloud.pcd"
  // Writes `cloud` (PLY or PCD by its extension, atomically): the caller's, since PCD goes through PCL
  // (io/pcd.h, hf_io_pcl), which hf_slam does not link. Required with `cloud`.
  std::function<void(const std::string& path, const PointCloud& cloud)> write_cloud;
};

std::vector<std::string> write_run_outputs(const std::string& dir, const SequenceRun& run, const RunSummary& summary,
                                           const Pipeline& pipeline, const FrameSource& source,
                                           const RunOutputOptions& extra = {});

// The surface as a point cloud: the mesh's vertices with their colours and normals.
PointCloud surface_cloud(const TriangleMesh& mesh);

}  // namespace hf::slam
