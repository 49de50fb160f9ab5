#include "slam/sequence_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "core/progress.h"
#include "fusion/voxel_block_grid.h"
#include "io/image_io.h"
#include "fusion/volume_io.h"
#include "io/ply.h"
#include "slam/eval_plot.h"

namespace hf::slam {

long SequenceRun::frames_lost() const {
  long n = 0;
  for (const auto& f : frames) n += f.state == TrackState::lost;
  return n;
}

Trajectory SequenceRun::estimate() const {
  Trajectory t;
  bool placed = false;  // frames lost before the map was initialised have no pose to report
  const bool have_corrected = corrected.size() == frames.size();
  size_t dropped = 0;  // dropped_timestamps_s are in capture order, as the frames are
  for (size_t i = 0; i < frames.size(); ++i) {
    const FrameResult& f = frames[i];
    // The frames dropped before this one arrived were shown at the pose of the frame before them.
    for (; dropped < dropped_timestamps_s.size() && dropped_timestamps_s[dropped] < f.timestamp_s; ++dropped)
      if (placed && !t.empty()) t.push_back({dropped_timestamps_s[dropped], t.back().T_world_camera});
    placed = placed || f.pose_valid;
    if (placed) t.push_back({f.timestamp_s, have_corrected ? corrected[i] : f.T_world_camera});
  }
  for (; dropped < dropped_timestamps_s.size(); ++dropped)
    if (!t.empty()) t.push_back({dropped_timestamps_s[dropped], t.back().T_world_camera});
  return t;
}

Trajectory SequenceRun::online_estimate() const {
  Trajectory t;
  bool placed = false;
  for (const auto& f : frames) {
    placed = placed || f.pose_valid;
    if (placed) t.push_back({f.timestamp_s, f.T_world_camera});
  }
  return t;
}

Trajectory SequenceRun::tracked_estimate() const {
  Trajectory t;
  for (const auto& f : frames)
    if (f.pose_valid) t.push_back({f.timestamp_s, f.T_world_camera});
  return t;
}

SequenceRun run_sequence(FrameSource& source, Pipeline& pipeline, const RunControl& control) {
  SequenceRun run;
  // A live source has no length: it runs until --max-frames, Ctrl-C or its device ends it.
  const bool unbounded = source.size() == kUnknownFrameCount;
  const long available = unbounded ? std::numeric_limits<long>::max() : long(source.size());
  const long total = control.max_frames > 0 ? std::min(control.max_frames, available) : available;
  std::unique_ptr<Progress> progress;
  if (!control.progress_label.empty())
    progress = std::make_unique<Progress>(control.progress_label,
                                          total == std::numeric_limits<long>::max() ? 0 : total);
  if (control.realtime) pipeline.set_realtime(true);
  const auto start = std::chrono::steady_clock::now();
  long read = 0;
  double busy_ms = 0.0;
  while (read < total) {
    if (control.stop && control.stop->load()) {
      run.interrupted = true;
      break;
    }
    const auto t0 = std::chrono::steady_clock::now();
    FrameRead fr = source.next();
    const double read_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    if (fr.status == FrameStatus::end) {
      run.input_ended = fr.message;
      break;
    }
    ++read;
    if (fr.status == FrameStatus::bad_frame) {
      run.bad_frames.push_back("frame " + std::to_string(fr.frame.index) + ": " + fr.message);
      if (control.warn_bad_frames) std::cerr << "\nwarning: skipping frame " << fr.frame.index << ": " << fr.message << "\n";
      if (progress) progress->update(read, "bad frame");
      continue;
    }
    FrameResult r;
    try {
      r = pipeline.process(fr.frame);
    } catch (const fusion::CapacityError& e) {
      run.stopped_by = "frame " + std::to_string(fr.frame.index) + ": " + e.what();
      break;
    }
    r.ms.read = read_ms;
    if (fr.frame.arrival)
      run.latency_ms.push_back(
          std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - *fr.frame.arrival).count());
    busy_ms += r.ms.total();
    if (control.on_frame) control.on_frame(r);
    if (control.observe) control.observe(fr.frame, r);
    if (progress) {
      std::ostringstream status;
      status << std::fixed << std::setprecision(1) << (busy_ms > 0 ? 1000.0 * double(run.frames.size() + 1) / busy_ms : 0.0)
             << " fps " << to_string(r.state);
      if (r.registration && r.state != TrackState::lost) status << " (" << hf::to_string(r.registration->status) << ")";
      progress->update(read, status.str());
    }
    run.frames.push_back(std::move(r));
  }
  if (progress) progress->finish();
  run.finish_ms = pipeline.finish(control.global);
  run.corrected = pipeline.corrected_trajectory();
  if (const std::optional<CaptureStats> stats = source.capture_stats()) {
    // Only those before the last frame read: later ones arrived after the run stopped reading.
    const double last_s = run.frames.empty() ? -1e300 : run.frames.back().timestamp_s;
    for (double t : stats->dropped_timestamps_s)
      if (t < last_s) run.dropped_timestamps_s.push_back(t);
  }
  if (run.corrected.size() != run.frames.size()) run.corrected.clear();
  run.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return run;
}

std::optional<double> RunSummary::ate_rmse_m() const {
  if (!metrics) return std::nullopt;
  return metrics->ate_m.rmse;
}
std::optional<double> RunSummary::rpe_trans_m_per_s() const {
  if (!metrics || !metrics->rpe_trans_m_per_s) return std::nullopt;
  return metrics->rpe_trans_m_per_s->rmse;
}
std::optional<double> RunSummary::rpe_rot_deg_per_s() const {
  if (!metrics || !metrics->rpe_rot_deg_per_s) return std::nullopt;
  return metrics->rpe_rot_deg_per_s->rmse;
}

namespace {

// Evaluation needs ground truth and enough poses; anything else means "not evaluated", not an error.
std::optional<EvalResult> try_evaluate(const Trajectory& gt, const Trajectory& est) {
  if (gt.empty() || est.size() < kMinAtePairs) return std::nullopt;
  try {
    return evaluate_trajectory(gt, est);
  } catch (const Error&) {
    return std::nullopt;  // e.g. no pose pairs within the time tolerance
  }
}

nlohmann::json opt(const std::optional<double>& v) { return v ? nlohmann::json(*v) : nlohmann::json(nullptr); }

}  // namespace

RunSummary summarize(const SequenceRun& run, const Pipeline& pipeline, const FrameSource& source,
                     const std::string& input) {
  RunSummary s;
  s.input = input;
  s.source_name = source.name();
  s.registration = pipeline.config().registration;
  s.backend = pipeline.config().backend;
  s.voxel_m = pipeline.config().volume.voxel_m;
  s.frames = long(run.frames.size());
  s.frames_bad = long(run.bad_frames.size());
  s.interrupted = run.interrupted;
  s.capture = source.capture_stats();
  if (s.capture) s.capture->dropped_timestamps_s.clear();  // in the run (SequenceRun), not repeated here
  s.realtime = pipeline.realtime();
  if (!run.latency_ms.empty()) {
    std::vector<double> l = run.latency_ms;
    std::sort(l.begin(), l.end());
    const auto at = [&](double q) { return l[std::min(l.size() - 1, size_t(std::ceil(q * double(l.size()))) - 1)]; };
    s.latency_p50_ms = at(0.5);
    s.latency_p95_ms = at(0.95);
    s.latency_max_ms = l.back();
  }
  const ColourCheck& colour = pipeline.colour_check();
  s.colour_verdict = to_string(colour.verdict());
  s.tracking_registration = pipeline.tracking_registration();
  if (colour.verdict() != ColourVerdict::undecided) {
    s.colour_median_scale = colour.median_scale();
    s.colour_decided_at_frame = colour.decided_at_frame();
  }
  // The primary of a frame: the configured method, or the depth-only one after an "unregistered" verdict.
  const auto primary_of = [&](size_t index) {
    return colour.verdict() == ColourVerdict::unregistered && index > colour.decided_at_frame()
               ? s.tracking_registration
               : s.registration;
  };
  StageMs sum;
  long spell = 0;
  for (const auto& f : run.frames) {
    s.frames_lost += f.state == TrackState::lost;
    s.frames_odometry += f.state == TrackState::odometry;
    s.frames_relocalised += f.state == TrackState::relocalised;
    s.frames_fallback += f.pose_valid && !f.method.empty() && f.method != primary_of(f.index) &&
                         f.state != TrackState::relocalised;
    s.frames_seeded_on_failure += f.seeded_on_failure;
    s.frames_placed_by_seed += f.placed_by_seed;
    s.frames_wide_basin += f.wide_basin;
    s.coverage += f.pose_valid ? 1.0 : 0.0;
    spell = f.state == TrackState::lost ? spell + 1 : 0;
    s.lost_spells += spell == 1;
    s.longest_lost_spell = std::max(s.longest_lost_spell, spell);
    s.worst_frame_ms = std::max(s.worst_frame_ms, f.ms.total());
    s.loop_worst_ms = std::max(s.loop_worst_ms, f.ms.loop);
    s.frames_reintegrated += f.reintegrated;
    s.refusion_backlog_max = std::max(s.refusion_backlog_max, f.refusion_backlog);
    if (f.loop_applied) {
      ++s.backend_jobs;
      s.backend_job_mean_ms += f.backend_job_ms;
      s.backend_job_worst_ms = std::max(s.backend_job_worst_ms, f.backend_job_ms);
    }
    if (f.registration && f.state != TrackState::lost) {
      s.frames_degenerate += f.registration->status == RegistrationStatus::degenerate;
      s.frames_poor += f.registration->status == RegistrationStatus::poor;
    }
    sum.read += f.ms.read;
    sum.preprocess += f.ms.preprocess;
    sum.track += f.ms.track;
    sum.relocalise += f.ms.relocalise;
    sum.integrate += f.ms.integrate;
    sum.raycast += f.ms.raycast;
    sum.keyframe += f.ms.keyframe;
    sum.loop += f.ms.loop;
    sum.reintegrate += f.ms.reintegrate;
  }
  s.loops_closed = pipeline.loops_closed();
  s.finish_ms = run.finish_ms;
  s.keyframes = pipeline.keyframes().size();
  if (s.frames > 0) {
    const double n = double(s.frames);
    s.coverage /= n;
    s.mean_ms = {sum.read / n,     sum.preprocess / n, sum.track / n, sum.relocalise / n, sum.integrate / n,
                 sum.raycast / n, sum.keyframe / n,   sum.loop / n,  sum.reintegrate / n};
    s.fps = sum.total() > 0 ? 1000.0 * n / sum.total() : 0.0;
    std::vector<double> totals;
    totals.reserve(run.frames.size());
    for (const auto& f : run.frames) totals.push_back(f.ms.total());
    const size_t quarter = std::max<size_t>(1, totals.size() / 4);
    double first = 0.0, last = 0.0;
    for (size_t i = 0; i < quarter; ++i) {
      first += totals[i];
      last += totals[totals.size() - quarter + i];
    }
    s.first_quarter_ms = first / double(quarter);
    s.last_quarter_ms = last / double(quarter);
    std::sort(totals.begin(), totals.end());
    s.p95_frame_ms = totals[std::min(totals.size() - 1, size_t(std::ceil(0.95 * double(totals.size()))) - 1)];
  }
  if (s.backend_jobs > 0) s.backend_job_mean_ms /= double(s.backend_jobs);
  if (auto eval = try_evaluate(source.ground_truth(), run.estimate())) s.metrics = eval->metrics();
  if (auto eval = try_evaluate(source.ground_truth(), run.tracked_estimate()))
    s.ate_tracked_only_m = eval->metrics().ate_m.rmse;
  if (auto eval = try_evaluate(source.ground_truth(), run.online_estimate()))
    s.ate_online_m = eval->metrics().ate_m.rmse;
  const auto& grid = pipeline.map();
  s.blocks_allocated = grid.block_count() + pipeline.store().size();
  s.memory_bytes = grid.memory_bytes();
  const size_t voxels = grid.block_count() * size_t(HF_BLOCK_SIZE * HF_BLOCK_SIZE * HF_BLOCK_SIZE);
  s.bytes_per_voxel = voxels ? double(grid.memory_bytes()) / double(voxels) : 0.0;
  return s;
}

nlohmann::json summary_to_json(const RunSummary& s, const SequenceRun& run, const Pipeline& pipeline,
                               const FrameSource& source) {
  nlohmann::json j;
  auto text_or_null = [](const std::string& t) { return t.empty() ? nlohmann::json(nullptr) : nlohmann::json(t); };
  j["version"] = text_or_null(s.version);
  j["commit"] = text_or_null(s.commit);
  j["command_line"] = text_or_null(s.command_line);
  j["started_utc"] = text_or_null(s.started_utc);
  j["input"] = s.input;
  j["source"] = s.source_name;
  const PinholeCamera& c = source.camera();
  j["camera"] = {{"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy}, {"width", c.width}, {"height", c.height}};
  j["camera_origin"] = source.camera_origin();
  j["registration"] = s.registration;
  j["backend"] = s.backend;
  j["devices"] = pipeline.stage_devices();
  j["voxel_m"] = s.voxel_m;
  j["frames"] = s.frames;
  j["frames_bad"] = s.frames_bad;
  j["frames_lost"] = s.frames_lost;
  j["frames_degenerate"] = s.frames_degenerate;
  j["frames_poor"] = s.frames_poor;
  j["frames_odometry"] = s.frames_odometry;
  j["frames_relocalised"] = s.frames_relocalised;
  j["frames_fallback"] = s.frames_fallback;
  j["frames_seeded_on_failure"] = s.frames_seeded_on_failure;
  j["frames_placed_by_seed"] = s.frames_placed_by_seed;
  j["frames_wide_basin"] = s.frames_wide_basin;
  j["coverage"] = s.coverage;
  j["lost_spells"] = s.lost_spells;
  j["longest_lost_spell"] = s.longest_lost_spell;
  j["keyframes"] = s.keyframes;
  j["worst_frame_ms"] = s.worst_frame_ms;
  j["ate_tracked_only_m"] = opt(s.ate_tracked_only_m);
  j["ate_online_m"] = opt(s.ate_online_m);
  j["loops_closed"] = s.loops_closed;
  j["frames_reintegrated"] = s.frames_reintegrated;
  j["loop_worst_ms"] = s.loop_worst_ms;
  j["slam_backend"] = {{"jobs", s.backend_jobs},
                       {"job_mean_ms", s.backend_job_mean_ms},
                       {"job_worst_ms", s.backend_job_worst_ms},
                       {"refusion_backlog_max", s.refusion_backlog_max},
                       {"refusion_backlog_end", pipeline.fused_frames().pending()},
                       {"window_edges", pipeline.window_edges().size()},
                       {"window_registrations", pipeline.window_registrations()},
                       {"window_solves", pipeline.window_solves()}};
  j["frame_ms"] = {{"p95", s.p95_frame_ms}, {"first_quarter_mean", s.first_quarter_ms},
                   {"last_quarter_mean", s.last_quarter_ms}, {"worst", s.worst_frame_ms}};
  j["finish_ms"] = s.finish_ms;
  j["interrupted"] = s.interrupted;
  j["stopped_by"] = run.stopped_by.empty() ? nlohmann::json(nullptr) : nlohmann::json(run.stopped_by);
  j["input_ended"] = run.input_ended.empty() ? nlohmann::json(nullptr) : nlohmann::json(run.input_ended);
  j["realtime"] = s.realtime;
  if (s.capture)
    j["capture"] = {{"frames_captured", s.capture->captured}, {"frames_processed", s.capture->delivered},
                    {"frames_dropped", s.capture->dropped},   {"input_fps", s.capture->input_fps},
                    {"processed_fps", s.capture->delivered_fps},
                    {"latency_ms", {{"p50", opt(s.latency_p50_ms)}, {"p95", opt(s.latency_p95_ms)},
                                    {"max", opt(s.latency_max_ms)}}}};
  else
    j["capture"] = nullptr;
  j["ate_rmse_m"] = opt(s.ate_rmse_m());
  j["rpe_trans_m_per_s"] = opt(s.rpe_trans_m_per_s());
  j["rpe_rot_deg_per_s"] = opt(s.rpe_rot_deg_per_s());
  j["metrics"] = s.metrics ? metrics_to_json(*s.metrics) : nlohmann::json(nullptr);
  j["colour_check"] = {{"verdict", s.colour_verdict},
                        {"median_scale", s.colour_median_scale},
                        {"decided_at_frame", s.colour_decided_at_frame ? nlohmann::json(*s.colour_decided_at_frame)
                                                                       : nlohmann::json(nullptr)},
                        {"tracking_registration", s.tracking_registration}};
  j["fps"] = s.fps;
  j["wall_s"] = run.wall_s;
  j["ms_per_frame"] = {{"read", s.mean_ms.read},         {"preprocess", s.mean_ms.preprocess},
                       {"track", s.mean_ms.track},       {"relocalise", s.mean_ms.relocalise},
                       {"integrate", s.mean_ms.integrate}, {"raycast", s.mean_ms.raycast},
                       {"keyframe", s.mean_ms.keyframe}, {"loop", s.mean_ms.loop},
                       {"reintegrate", s.mean_ms.reintegrate}, {"total", s.mean_ms.total()}};
  j["blocks_allocated"] = s.blocks_allocated;
  j["bytes_per_voxel"] = s.bytes_per_voxel;
  j["memory_bytes"] = s.memory_bytes;
  j["config"] = config_to_json(pipeline.config());
  j["bad_frames"] = run.bad_frames;
  nlohmann::json frames = nlohmann::json::array();
  for (const auto& f : run.frames) {
    nlohmann::json fj = {{"index", f.index}, {"timestamp_s", f.timestamp_s}, {"state", to_string(f.state)},
                         {"integrated", f.integrated}, {"keyframe", f.keyframe}, {"ms", f.ms.total()}};
    if (!f.method.empty()) fj["method"] = f.method;
    if (f.loop_closed) fj["loop_closed"] = true;
    if (f.reintegrated) fj["reintegrated"] = f.reintegrated;
    fj["refusion_backlog"] = f.refusion_backlog;
    if (f.loop_applied) fj["backend_job_ms"] = f.backend_job_ms;
    if (f.registration) {
      fj["registration_status"] = hf::to_string(f.registration->status);
      fj["inlier_ratio"] = f.registration->inlier_ratio;
      fj["inliers"] = f.registration->inliers;
      fj["degenerate_dims"] = f.registration->degenerate_dims;
    }
    if (!f.message.empty()) fj["message"] = f.message;
    if (f.seeded_on_failure) fj["seeded_on_failure"] = true;
    if (f.placed_by_seed) fj["placed_by_seed"] = true;
    if (f.wide_basin) fj["wide_basin"] = true;
    if (f.term_disagreement.valid)
      fj["terms"] = {{"chi2", f.term_disagreement.chi2},
                     {"translation_m", f.term_disagreement.translation_m},
                     {"rotation_deg", f.term_disagreement.rotation_deg}};
    if (f.colour_alignment)
      fj["colour_alignment"] = {{"valid", f.colour_alignment->valid},
                                {"scale", f.colour_alignment->scale},
                                {"shift_px", {f.colour_alignment->shift_x_px, f.colour_alignment->shift_y_px}},
                                {"chamfer_px", f.colour_alignment->chamfer_px},
                                {"zoom_contrast_px", f.colour_alignment->zoom_contrast_px},
                                {"depth_edges", f.colour_alignment->depth_edges}};
    frames.push_back(std::move(fj));
  }
  j["per_frame"] = std::move(frames);
  return j;
}

namespace {

std::string fmt(double v, int precision) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(precision) << v;
  return o.str();
}

std::string colour_line(const RunSummary& s) {
  if (s.colour_verdict == "undecided") return "registration to depth undecided (the check did not run or had too few frames)";
  std::string line = "judged " + s.colour_verdict + " to depth at frame " +
                     std::to_string(s.colour_decided_at_frame.value_or(0)) + " (median colour / depth scale " +
                     fmt(s.colour_median_scale, 3) + ")";
  if (s.colour_verdict == "unregistered") line += "; tracked with " + s.tracking_registration + " from then on";
  return line;
}

std::string report_markdown(const RunSummary& s, const SequenceRun& run, const FrameSource& source) {
  std::ostringstream md;
  md << "# hashfusion run\n\n| | |\n|---|---|\n"
     << "| input | `" << s.input << "` (" << s.source_name << ") |\n"
     << "| camera | " << source.camera().describe() << " (" << source.camera_origin() << ") |\n"
     << "| registration | " << s.registration << " (backend " << s.backend << ") |\n"
     << "| colour | " << colour_line(s) << " |\n"
     << "| voxel | " << fmt(s.voxel_m * 1000.0, 1) << " mm |\n"
     << "| frames | " << s.frames << " processed, " << s.frames_bad << " unreadable, " << s.frames_lost << " lost, "
     << s.frames_degenerate << " degenerate, " << s.frames_poor << " poor, " << s.frames_odometry
     << " odometry only, " << s.frames_relocalised << " relocalised, " << s.frames_seeded_on_failure
     << " seeded on failure (" << s.frames_placed_by_seed << " placed by the retry), " << s.frames_wide_basin
     << " tracked with the wide basin (no motion prior)"
     << (s.interrupted ? " (interrupted)" : "") << (run.stopped_by.empty() ? "" : " (stopped early: " + run.stopped_by + ")")
     << " |\n"
     << "| coverage | " << fmt(100.0 * s.coverage, 1) << " % of frames with a pose; " << s.lost_spells
     << " lost spells, the longest " << s.longest_lost_spell << " frames |\n"
     << "| keyframes | " << s.keyframes << ", " << s.loops_closed << " loops closed, " << s.frames_reintegrated
     << " frames re-fused (worst loop stage " << fmt(s.loop_worst_ms, 1) << " ms, finish " << fmt(s.finish_ms, 0)
     << " ms) |\n"
     << "| back-end | " << s.backend_jobs << " jobs beside tracking (" << fmt(s.backend_job_mean_ms, 1)
     << " ms mean, worst " << fmt(s.backend_job_worst_ms, 1) << " ms on the back-end thread); re-fusion backlog at "
     << "most " << s.refusion_backlog_max << " frames, 0 after the run |\n"
     << (s.capture ? "| capture | " + std::to_string(s.capture->captured) + " frames in at " +
                         fmt(s.capture->input_fps, 1) + " fps, " + std::to_string(s.capture->delivered) +
                         " processed at " + fmt(s.capture->delivered_fps, 1) + " fps, " +
                         std::to_string(s.capture->dropped) + " dropped (processing slower than the sensor)" +
                         (run.input_ended.empty() ? "" : "; input ended: " + run.input_ended) + " |\n" +
                         (s.latency_p50_ms ? "| latency | arrival to pose: p50 " + fmt(*s.latency_p50_ms, 1) +
                                                 " ms, p95 " + fmt(*s.latency_p95_ms, 1) + " ms, max " +
                                                 fmt(*s.latency_max_ms, 1) + " ms |\n"
                                           : std::string())
                   : std::string())
     << (s.realtime ? "| timing | realtime mode: back-end results applied when ready and re-fusion by its ms budget, "
                      "so this run depends on the machine's timing |\n"
                    : std::string())
     << "| speed | " << fmt(s.fps, 1) << " fps (" << fmt(s.mean_ms.total(), 1) << " ms per frame, p95 "
     << fmt(s.p95_frame_ms, 1) << ", worst " << fmt(s.worst_frame_ms, 1) << " ms; first quarter "
     << fmt(s.first_quarter_ms, 1) << ", last quarter " << fmt(s.last_quarter_ms, 1) << " ms) |\n"
     << "| map | " << s.blocks_allocated << " blocks, " << fmt(double(s.memory_bytes) / (1 << 20), 1) << " MiB, "
     << fmt(s.bytes_per_voxel, 2) << " bytes per voxel |\n\n"
     << "## Milliseconds per frame (tracking thread)\n\n"
     << "| read | preprocess | track | relocalise | integrate | raycast | keyframe | loop | re-fuse | total |\n"
     << "|---|---|---|---|---|---|---|---|---|---|\n| " << fmt(s.mean_ms.read, 1) << " | "
     << fmt(s.mean_ms.preprocess, 1)
     << " | " << fmt(s.mean_ms.track, 1) << " | " << fmt(s.mean_ms.relocalise, 1) << " | "
     << fmt(s.mean_ms.integrate, 1) << " | " << fmt(s.mean_ms.raycast, 1) << " | " << fmt(s.mean_ms.keyframe, 1)
     << " | " << fmt(s.mean_ms.loop, 1) << " | " << fmt(s.mean_ms.reintegrate, 1)
     << " | " << fmt(s.mean_ms.total(), 1) << " |\n\n## Trajectory error (every frame, lost ones at their reported pose)\n\n";
  if (s.metrics) {
    md << format_metrics_markdown(*s.metrics);
  } else {
    md << "not evaluated (no ground truth, or fewer than " << kMinAtePairs << " tracked poses)\n";
  }
  size_t listed = 0;
  std::ostringstream lost;
  for (const auto& f : run.frames)
    if (f.state == TrackState::lost && listed++ < 20) lost << "- frame " << f.index << ": " << f.message << "\n";
  if (listed) md << "\n## Lost frames\n\n" << lost.str() << (listed > 20 ? "- ...\n" : "");
  if (!run.bad_frames.empty()) {
    md << "\n## Unreadable frames (skipped)\n\n";
    for (const auto& b : run.bad_frames) md << "- " << b << "\n";
  }
  return md.str();
}

}  // namespace

const std::vector<std::string>& run_output_names() {
  static const std::vector<std::string> names = {"trajectory.txt", "mesh.ply",  "report.json", "report.md",
                                                 "render.png",     "trajectory.png", "map.hfmap", "cloud.ply",
                                                 "cloud.pcd"};
  return names;
}

PointCloud surface_cloud(const TriangleMesh& mesh) {
  PointCloud cloud;
  cloud.positions = mesh.vertices;
  cloud.normals = mesh.normals;
  cloud.colors = mesh.colors;
  return cloud;
}

std::vector<std::string> write_run_outputs(const std::string& dir, const SequenceRun& run, const RunSummary& summary,
                                           const Pipeline& pipeline, const FrameSource& source,
                                           const RunOutputOptions& extra) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) throw Error(dir + ": cannot create output folder");
  // Decide the whole set first, so report.json can list it and stale files of ours can go.
  ColorImage shaded;
  if (const auto pose = pipeline.last_good_pose()) shaded = pipeline.render(*pose);
  const std::optional<EvalResult> eval = try_evaluate(source.ground_truth(), run.estimate());
  std::vector<std::string> names = {"trajectory.txt", "mesh.ply", "report.json", "report.md"};
  if (!shaded.empty()) names.push_back("render.png");
  if (eval) names.push_back("trajectory.png");
  auto path_of = [&](const std::string& name) {
    return std::filesystem::path(name).is_absolute() ? name : dir + "/" + name;
  };
  // Extra outputs named by a bare file name land in the folder and belong to its set.
  for (const std::string* extra_name : {&extra.map, &extra.cloud})
    if (!extra_name->empty() && std::filesystem::path(*extra_name).parent_path().empty()) names.push_back(*extra_name);
  std::vector<std::string> written;

  write_tum_trajectory(path_of("trajectory.txt"), run.estimate(),
                       "hashfusion run --registration " + summary.registration + "\ninput: " + summary.input);
  written.push_back(path_of("trajectory.txt"));

  PlyWriteOptions ply;
  ply.comment = "hashfusion " + summary.registration + " on " + summary.input;
  const TriangleMesh mesh = pipeline.extract_mesh();
  write_ply(path_of("mesh.ply"), mesh, ply);
  written.push_back(path_of("mesh.ply"));
  if (!extra.map.empty()) {
    fusion::save_volume(path_of(extra.map), pipeline.map(), &pipeline.store());
    written.push_back(path_of(extra.map));
  }
  if (!extra.cloud.empty()) {
    if (!extra.write_cloud) throw Error("write_run_outputs: a cloud without a writer");
    extra.write_cloud(path_of(extra.cloud), surface_cloud(mesh));
    written.push_back(path_of(extra.cloud));
  }

  nlohmann::json j = summary_to_json(summary, run, pipeline, source);
  j["outputs"] = names;
  write_file_atomically(path_of("report.json"), [&](std::ostream& out) { out << j.dump(2) << "\n"; });
  written.push_back(path_of("report.json"));

  const std::string md = report_markdown(summary, run, source);
  write_file_atomically(path_of("report.md"), [&](std::ostream& out) { out << md; });
  written.push_back(path_of("report.md"));

  if (!shaded.empty()) {
    write_color_png(path_of("render.png"), shaded);
    written.push_back(path_of("render.png"));
  }
  if (eval) {
    TrajectoryPlotOptions o;
    o.title = "hashfusion " + summary.registration + ": " + summary.input;
    write_trajectory_plot(path_of("trajectory.png"), source.ground_truth(), run.estimate(), *eval, o);
    written.push_back(path_of("trajectory.png"));
  }
  // An earlier run's render.png or trajectory.png beside this run's outputs would describe another run.
  for (const std::string& name : run_output_names())
    if (std::find(names.begin(), names.end(), name) == names.end()) std::filesystem::remove(path_of(name), ec);
  return written;
}

}  // namespace hf::slam
