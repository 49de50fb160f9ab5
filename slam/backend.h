// The SLAM back-end: loop closure beside the tracking thread (slam/pipeline.h, stage `close_loops`).
//
//   tracking thread (Pipeline::process)                   back-end thread "hf-backend" (BackendThread)
//   frame s:   LoopJob job = snapshot(...)  ---- submit --> LoopCloser::run(job): odometry edges, loop
//                                                           candidates, verification, pose-graph solves
//   frame s+d: LoopJobResult r = wait()    <--- result ---  (the tracker waits here only when the job is late)
//              keyframes, loops and the current pose take r; re-fusion is scheduled
//
// A job owns everything it reads (LoopJob holds copies: keyframe poses, loop edges, the new keyframes' compressed
// images and appearance matches), so the two threads share no mutable state; the result is applied by the
// tracking thread between two frames, so nothing the tracker reads changes under it.
//
// Determinism: a job's inputs are a function of the frames processed so far, its computation of its inputs alone
// (its own registration objects and CPU reductions, a pose-graph solve bounded by iterations, not by time, and a
// TBB arena of its own), and it is applied at a fixed frame (snapshot frame + apply_delay_frames). So an offline run
// gives the same trajectory bit for bit whether the job ran on the thread, inline, early or late. Only the
// realtime mode (Pipeline::set_realtime: live input, replay at the recorded rate) applies a result at the first
// frame after it is ready, and honours the graph's time budget: its results depend on timing.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <functional>
#include <future>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/camera.h"
#include "core/se3.h"
#include "registration/frame_pyramid.h"
#include "registration/registration.h"
#include "slam/appearance.h"
#include "slam/keyframes.h"
#include "slam/loop_closure.h"

namespace hf::slam {

// One thread with a name (visible to top, gdb and perf as `name`) that runs submitted tasks one at a time, in
// order, at a lower scheduling priority than the thread that submits them (Linux: nice +5 for this thread only), so
// on a loaded machine the tracking thread is served first. Tasks run inside a TBB arena of one thread: their
// parallel loops stay on this thread and never take the tracking thread's workers.
// Thread-safety: submit() from one thread (the owner); the returned futures anywhere. The destructor runs the
// tasks already submitted and joins.
class BackendThread {
 public:
  explicit BackendThread(std::string name);
  ~BackendThread();
  BackendThread(const BackendThread&) = delete;
  BackendThread& operator=(const BackendThread&) = delete;

  // Queues `task`; its exceptions come out of the future's get().
  std::future<void> submit(std::function<void()> task);
  const std::string& name() const { return name_; }

 private:
  void run();

  std::string name_;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::vector<std::packaged_task<void()>> queue_;  // guarded by mutex_
  bool stop_ = false;                               // guarded by mutex_
  std::thread thread_;                              // last: started once the members above exist
};

// A keyframe a job searches loops for: its images as the keyframe stores them, and what the appearance index
// retrieved for it when it was added (queried on the tracking thread, which owns the index).
struct LoopJobKeyframe {
  size_t id = 0;
  CompressedRgbd images;
  std::vector<AppearanceMatch> matches;
};

// Keyframe k's pose, edges and bookkeeping without its images (a job must not copy every keyframe's images).
Keyframe keyframe_metadata(const Keyframe& k);

// Everything one back-end job reads, copied at the snapshot frame.
struct LoopJob {
  size_t snapshot_frame = 0;              // Pipeline::frames_processed() when taken
  std::vector<Keyframe> keyframes;        // every keyframe's pose and edges, images left empty
  std::vector<bool> has_images;           // per keyframe: images still kept (KeyframeMap::has_images)
  std::vector<LoopEdge> loops;            // the verified loops so far
  std::vector<LoopEdge> window;           // the keyframe window edges so far (LoopClosureOptions::window_keyframes)
  std::vector<LoopJobKeyframe> added;     // the keyframes new since the last job, oldest first (ids ascending)
  std::string method;                     // the registration that verifies (the tracking primary's name)
  RegistrationOptions method_options;
  bool time_budget = false;               // honour loop_closure.time_budget_ms (realtime mode only)
};

struct LoopJobResult {
  size_t snapshot_frame = 0;
  size_t keyframes = 0;                   // LoopJob::keyframes.size(): the keyframes T_world_keyframe covers
  // Per added keyframe: its odometry edge as registered against the previous keyframe, when measured.
  struct Odometry {
    size_t id = 0;
    SE3 T_previous_this;
    Matrix6d information;
  };
  std::vector<Odometry> odometry;
  std::vector<LoopEdge> loops;            // the whole list after the job (new loops appended, rejected ones gone)
  std::vector<LoopEdge> window;           // the whole list of window edges after the job (new ones appended)
  size_t loops_closed = 0;                // solves that closed a loop and moved the keyframes
  size_t window_solves = 0;               // solves for new window edges alone that moved the keyframes
  size_t window_registrations = 0;        // window pairs registered by this job (verified or not)
  // The keyframes' poses after the last solve that moved them; empty when no solve moved them.
  std::vector<SE3> T_world_keyframe;
  double ms = 0.0;                        // the job's own wall time on the back-end
};

// The back-end's loop closure: a job at a time, keeping between jobs only what later jobs of the same run need
// (the newest keyframe's pyramid for the next odometry edge, the keyframes' compressed images for verification,
// the verifying registration). What it does per added keyframe k, in order: (1) register k against keyframe k-1's
// own images (the odometry edge, kept when good, consistent and not degenerate); (2) candidates among the
// keyframes (slam/loop_closure.h loop_candidates, from the job's current poses); (3) each candidate registered
// from the relative pose their poses imply, verified by inlier ratio and depth agreement; (4) when a loop was
// verified, the keyframe graph solved (loops the graph's consistency test rejects are dropped; when it rejects
// all new ones nothing moves), and the job's poses take the solution before the next added keyframe. With
// window_keyframes > 0, (1b) after (1): k registered against keyframes k-2 .. k-window_keyframes from their current
// relative pose and verified as a loop is, each verified pair a window edge; (4) then also runs when k added a
// window edge and no loop (a local bundle adjustment of the keyframe poses).
// Thread-safety: none; one run() at a time (the pipeline submits the next job only after the last one's result).
class LoopCloser {
 public:
  LoopCloser(const LoopClosureOptions& options, const FramePyramidOptions& pyramid, int tracking_level,
             const PinholeCamera& camera, double voxel_m);

  LoopJobResult run(LoopJob job);

  size_t images_kept() const { return images_.size(); }

 private:
  std::optional<RegistrationResult> verify(const FramePyramid& current, const FramePyramid& reference,
                                           const SE3& guess);
  FramePyramid pyramid_of(const CompressedRgbd& images) const;

  LoopClosureOptions options_;
  FramePyramidOptions pyramid_options_;
  PinholeCamera camera_, tracking_camera_;
  double voxel_m_;
  std::unique_ptr<Registration> verifier_;
  std::string verifier_name_;
  std::optional<FramePyramid> last_keyframe_pyramid_;  // the newest keyframe run so far, for the next odometry edge
  // The newest keyframes' pyramids (at most window_keyframes), for the window edges without decoding them again.
  std::map<size_t, FramePyramid> window_pyramids_;
  std::map<size_t, CompressedRgbd> images_;            // keyframe id -> images, while the keyframe keeps them
};

}  // namespace hf::slam
