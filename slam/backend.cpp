#include "slam/backend.h"

#include <pthread.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <tbb/task_arena.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <utility>

#include "registration/reduction.h"
#include "slam/consistency.h"
#include "slam/pose_graph.h"

namespace hf::slam {
namespace backend_detail {

double ms_between(std::chrono::steady_clock::time_point t0, std::chrono::steady_clock::time_point t1) {
  return std::chrono::duration<double, std::milli>(t1 - t0).count();
}

// A pose-graph solve bounded by its iterations alone: a solve cut by the clock would end at a different iterate on
// a busier machine. 1e9 ms is "never" for any session.
constexpr double kNoTimeBudgetMs = 1e9;

}  // namespace backend_detail

Keyframe keyframe_metadata(const Keyframe& k) {
  Keyframe m;
  m.id = k.id;
  m.frame_index = k.frame_index;
  m.timestamp_s = k.timestamp_s;
  m.T_world_camera = k.T_world_camera;
  m.T_previous_this = k.T_previous_this;
  m.path_m = k.path_m;
  m.information = k.information;
  m.T_previous_this_registered = k.T_previous_this_registered;
  m.odometry_information = k.odometry_information;
  return m;
}

// --- BackendThread -----------------------------------------------------------------------------------------------

BackendThread::BackendThread(std::string name) : name_(std::move(name)), thread_([this] { run(); }) {}

BackendThread::~BackendThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

std::future<void> BackendThread::submit(std::function<void()> task) {
  std::packaged_task<void()> t(std::move(task));
  std::future<void> f = t.get_future();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    queue_.push_back(std::move(t));
  }
  wake_.notify_one();
  return f;
}

void BackendThread::run() {
  // Linux names threads by at most 15 characters; the name is for people (top -H, gdb, perf).
  pthread_setname_np(pthread_self(), name_.substr(0, 15).c_str());
  // Linux applies a nice value to the calling thread alone when given its thread id: the back-end yields the
  // cores to tracking when both want them. It cannot starve: a tracker that needs its result blocks (no spin).
  (void)setpriority(PRIO_PROCESS, id_t(syscall(SYS_gettid)), 5);
  tbb::task_arena arena(1);
  for (;;) {
    std::packaged_task<void()> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop_ and nothing left to run
      task = std::move(queue_.front());
      queue_.erase(queue_.begin());
    }
    arena.execute([&] { task(); });
  }
}

// --- LoopCloser --------------------------------------------------------------------------------------------------

LoopCloser::LoopCloser(const LoopClosureOptions& options, const FramePyramidOptions& pyramid, int tracking_level,
                       const PinholeCamera& camera, double voxel_m)
    : options_(options), pyramid_options_(pyramid), camera_(camera), tracking_camera_(camera.scaled(tracking_level)),
      voxel_m_(voxel_m) {
  pyramid_options_.first_level = tracking_level;
}

FramePyramid LoopCloser::pyramid_of(const CompressedRgbd& images) const {
  const DepthImage depth = images.depth();
  const ColorImage colour = images.colour();
  return build_frame_pyramid(depth, colour.empty() ? nullptr : &colour, camera_, pyramid_options_);
}

// One keyframe pair registered and verified (loop_closure.min_inlier_ratio and min_consistent): the result when
// the registration is good and the depths agree where they overlap.
std::optional<RegistrationResult> LoopCloser::verify(const FramePyramid& current, const FramePyramid& reference,
                                                     const SE3& guess) {
  RegistrationResult reg = verifier_->align(current, reference, guess);
  if (reg.status != RegistrationStatus::good || reg.inlier_ratio < options_.min_inlier_ratio) return std::nullopt;
  const Consistency cons = depth_consistency(current.levels[0].vertices, depth_of(reference.levels[0].vertices),
                                             tracking_camera_, reg.T_ref_cur, voxel_m_);
  if (cons.overlap == 0 || double(cons.consistent) < options_.min_consistent * double(cons.overlap))
    return std::nullopt;
  return reg;
}

LoopJobResult LoopCloser::run(LoopJob job) {
  const auto t0 = std::chrono::steady_clock::now();
  LoopJobResult out;
  out.snapshot_frame = job.snapshot_frame;
  out.keyframes = job.keyframes.size();
  // The verifier is the tracking primary (keyframe pairs often see one wall and a floor, which leaves ICP alone
  // degenerate), an object of the back-end's own: a registration keeps a history (combined's photometric regime)
  // that the tracker's must not share. Reductions on the CPU: the device context belongs to the tracking thread.
  if (!verifier_ || verifier_name_ != job.method) {
    verifier_ = make_registration(job.method, job.method_options, make_backend("cpu"));
    verifier_name_ = job.method;
  }
  for (size_t i = 0; i < job.has_images.size(); ++i)
    if (!job.has_images[i]) images_.erase(i);  // dropped by the keyframes' memory budget: dropped here too

  // The job's own copy of the graph's inputs; poses move with each solve that closes a loop.
  std::vector<Keyframe>& nodes = job.keyframes;
  std::vector<LoopEdge> loops = std::move(job.loops);
  std::vector<LoopEdge> window = std::move(job.window);
  const size_t window_keyframes = size_t(std::max(options_.window_keyframes, 0));
  bool moved = false;
  PoseGraphOptions graph = options_.graph;
  if (!job.time_budget) graph.time_budget_ms = backend_detail::kNoTimeBudgetMs;

  for (LoopJobKeyframe& added : job.added) {
    const size_t k = added.id;
    if (k >= nodes.size() || added.images.empty()) {  // images dropped for the budget before the job took them
      last_keyframe_pyramid_.reset();  // the next keyframe's odometry edge has no previous images to meet
      window_pyramids_.clear();        // nor the window edges (an image-less keyframe breaks the window)
      continue;
    }
    const FramePyramid kp = pyramid_of(added.images);
    // (1) The odometry edge, independent of the map (slam/keyframes.h Keyframe::T_previous_this_registered).
    if (k > 0 && last_keyframe_pyramid_ && last_keyframe_pyramid_->num_levels() > 0) {
      const std::optional<RegistrationResult> reg = verify(kp, *last_keyframe_pyramid_, nodes[k].T_previous_this);
      if (reg && reg->degenerate_dims == 0) {
        nodes[k].T_previous_this_registered = reg->T_ref_cur;
        nodes[k].odometry_information = reg->information;
        out.odometry.push_back({k, reg->T_ref_cur, reg->information});
      }
    }
    // (1b) Window edges to the keyframes before k-1 whose pyramids are still held, from the relative pose their
    // current poses imply (the graph's own estimate).
    size_t new_window = 0;
    if (window_keyframes >= 2) {
      for (size_t j = 2; j <= window_keyframes && j <= k; ++j) {
        const auto p = window_pyramids_.find(k - j);
        if (p == window_pyramids_.end() || p->second.num_levels() == 0) continue;
        const SE3 guess = nodes[k - j].T_world_camera.inverse() * nodes[k].T_world_camera;
        ++out.window_registrations;
        const std::optional<RegistrationResult> reg = verify(kp, p->second, guess);
        if (!reg || reg->degenerate_dims != 0) continue;
        window.push_back({k - j, k, reg->T_ref_cur, options_.window_information_scale * reg->information});
        ++new_window;
      }
      window_pyramids_[k] = kp;
      while (window_pyramids_.size() > window_keyframes) window_pyramids_.erase(window_pyramids_.begin());
    }
    images_[k] = std::move(added.images);
    last_keyframe_pyramid_ = kp;
    // (2) Candidates among the keyframes up to k, from the job's current poses.
    if (k == 0) continue;
    std::vector<bool> has_images(k + 1, false);
    for (size_t i = 0; i <= k; ++i) has_images[i] = images_.count(i) > 0;
    const std::vector<Keyframe> upto(nodes.begin(), nodes.begin() + std::ptrdiff_t(k + 1));
    const std::vector<size_t> candidates = loop_candidates(upto, has_images, k, added.matches, options_);
    if (candidates.empty() && new_window == 0) continue;
    // (3) Verification.
    size_t new_loops = 0;
    for (size_t c : candidates) {
      const FramePyramid cp = pyramid_of(images_.at(c));
      const SE3 guess = nodes[c].T_world_camera.inverse() * nodes[k].T_world_camera;
      const std::optional<RegistrationResult> reg = verify(kp, cp, guess);
      if (!reg) continue;
      loops.push_back({c, k, reg->T_ref_cur, reg->information});
      ++new_loops;
    }
    if (new_loops == 0 && new_window == 0) continue;
    // (4) The graph over the keyframes up to k: the later ones of this job were not made yet when the tracker
    // reached k, as far as the graph is concerned.
    const PoseGraphResult res =
        keyframe_graph(upto, loops, window, options_.tracking_information_scale_in_graph()).optimize(graph);
    if (!res.ok()) {
      loops.resize(loops.size() - new_loops);
      continue;
    }
    bool loop_closed = new_loops > 0;
    if (new_loops > 0 && res.loop_accepted.size() == loops.size()) {
      const size_t first = loops.size() - new_loops;
      std::vector<LoopEdge> kept(loops.begin(), loops.begin() + std::ptrdiff_t(first));
      for (size_t i = first; i < loops.size(); ++i)
        if (res.loop_accepted[i]) kept.push_back(loops[i]);
      loop_closed = kept.size() > first;
      loops = std::move(kept);
      // Every new loop rejected: nothing moves, unless window edges came with k (the solution is then the graph's
      // without the rejected loops, which optimize() solved again).
      if (!loop_closed && new_window == 0) continue;
    }
    if (res.T_world_node.size() != k + 1) continue;  // cannot happen: one node per keyframe
    // The keyframes after k move rigidly with k, as the tracker (and so every later keyframe) would have.
    const SE3 correction = res.T_world_node[k] * nodes[k].T_world_camera.inverse();
    for (size_t i = 0; i <= k; ++i) nodes[i].T_world_camera = res.T_world_node[i];
    for (size_t i = k + 1; i < nodes.size(); ++i) nodes[i].T_world_camera = correction * nodes[i].T_world_camera;
    if (loop_closed)
      ++out.loops_closed;
    else
      ++out.window_solves;
    moved = true;
  }
  out.loops = std::move(loops);
  out.window = std::move(window);
  if (moved)
    for (const Keyframe& n : nodes) out.T_world_keyframe.push_back(n.T_world_camera);
  out.ms = backend_detail::ms_between(t0, std::chrono::steady_clock::now());
  return out;
}

}  // namespace hf::slam
