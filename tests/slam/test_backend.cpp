// The SLAM back-end beside tracking (issue 33): the same trajectory bit for bit with the back-end on its thread or
// inline, and from one run to the next; the tracking thread's share of the back-end's work bounded per frame
// (counted in re-fused frames and backlog, never timed); re-fusion in proportion to what changed; the thread.
#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <vector>

#include "datasets/synthetic_source.h"
#include "slam/backend.h"
#include "slam/pipeline.h"
#include "slam/pose_graph.h"
#include "slam/reintegration.h"
#include "slam/sequence_run.h"
#include "tests/slam/pipeline_test_util.h"

namespace hf::slam {
namespace {

using test::half_res;

// A short session whose back-end has work: the `loop` preset's lap, cut short, at half resolution, with keyframes
// and loop candidates made easy (every ~5 cm, no path or gap requirement beyond 2 keyframes), so loops are verified
// and solved and frames re-fused within a few seconds of test time.
constexpr int kFrames = 40;

PipelineConfig busy_backend_config(bool background) {
  PipelineConfig c;
  c.volume.capacity_blocks = 1 << 15;
  c.keyframes.min_translation_m = 0.05;
  c.keyframes.min_rotation_deg = 5.0;
  c.loop_closure.min_keyframe_gap = 2;
  c.loop_closure.min_path_m = 0.0;
  c.loop_closure.background = background;
  c.loop_closure.apply_delay_frames = 4;
  c.reintegration.frames_per_step = 1;
  c.reintegration.frames_after_loop = 2;
  c.reintegration.frames_after_loop_per_step = 1;  // owed over two frames: the spreading is exercised
  return c;
}

struct BackendRun {
  SequenceRun run;
  RunSummary summary;
  size_t pending_after = 0;
};

BackendRun run_busy(bool background) {
  auto source = datasets::open_synthetic("loop", half_res("loop", kFrames));
  Pipeline pipeline(busy_backend_config(background), source->camera());
  BackendRun out;
  out.run = run_sequence(*source, pipeline);
  out.summary = summarize(out.run, pipeline, *source, "loop");
  out.pending_after = pipeline.fused_frames().pending();
  size_t first_loop = 0;
  for (const FrameResult& f : out.run.frames)
    if (f.loop_closed && first_loop == 0) first_loop = f.index;
  std::printf("back-end %s: %zu jobs, %zu loops (first applied at frame %zu), %zu keyframes, %zu re-fused, backlog "
              "max %zu\n",
              background ? "thread" : "inline", out.summary.backend_jobs, out.summary.loops_closed, first_loop,
              out.summary.keyframes, out.summary.frames_reintegrated, out.summary.refusion_backlog_max);
  return out;
}

// The threaded run both tests judge (run once per test binary: the suite's time is shared).
const BackendRun& threaded_run() {
  static const BackendRun run = run_busy(true);
  return run;
}

bool same_bits(const SE3& a, const SE3& b) { return a.matrix() == b.matrix(); }

TEST(Backend, SameTrajectoryBitForBitOnTheThreadInlineAndAgain) {
  const BackendRun& thread_a = threaded_run();
  const BackendRun thread_b = run_busy(true);
  const BackendRun inline_run = run_busy(false);
  // The back-end had work, or this test proves nothing.
  EXPECT_GE(thread_a.summary.backend_jobs, 3u);
  EXPECT_GE(thread_a.summary.loops_closed, 1u);
  EXPECT_GE(thread_a.summary.frames_reintegrated, 1u);
  for (const BackendRun* other : {&thread_b, &inline_run}) {
    ASSERT_EQ(other->run.frames.size(), thread_a.run.frames.size());
    ASSERT_EQ(other->run.corrected.size(), thread_a.run.corrected.size());
    for (size_t i = 0; i < thread_a.run.frames.size(); ++i) {
      EXPECT_TRUE(same_bits(other->run.frames[i].T_world_camera, thread_a.run.frames[i].T_world_camera)) << i;
      EXPECT_TRUE(same_bits(other->run.corrected[i], thread_a.run.corrected[i])) << i;
      EXPECT_EQ(other->run.frames[i].reintegrated, thread_a.run.frames[i].reintegrated) << i;
      EXPECT_EQ(other->run.frames[i].loop_applied, thread_a.run.frames[i].loop_applied) << i;
    }
    EXPECT_EQ(other->summary.loops_closed, thread_a.summary.loops_closed);
  }
}

// The cost the back-end puts on the tracking thread does not grow with the session: per frame at most
// frames_per_step re-fusions, plus at most frames_after_loop_per_step of the frames_after_loop a loop leaves owed
// (so no frame pays a loop's whole burst); at most one job applied per
// frame, one job in flight at a time (applied apply_delay_frames after it started); the backlog is reported per
// frame, never exceeds the frames stored, and is 0 after finish().
TEST(Backend, TrackingThreadShareIsBoundedPerFrameAndTheBacklogDrains) {
  const PipelineConfig c = busy_backend_config(true);
  const BackendRun& r = threaded_run();
  size_t stored = 0, applied = 0;
  for (const FrameResult& f : r.run.frames) {
    stored += f.integrated;
    const size_t allowed =
        size_t(c.reintegration.frames_per_step) + size_t(c.reintegration.frames_after_loop_per_step);
    EXPECT_LE(f.reintegrated, allowed) << "frame " << f.index;
    EXPECT_LE(f.refusion_backlog, stored) << "frame " << f.index;
    applied += f.loop_applied;
  }
  // Jobs are at least apply_delay_frames apart (one in flight), so the applications are bounded by the frames.
  EXPECT_LE(applied, r.run.frames.size() / size_t(c.loop_closure.apply_delay_frames) + 1);
  EXPECT_GE(r.summary.refusion_backlog_max, 1u);  // the backlog is real and reported...
  EXPECT_EQ(r.pending_after, 0u);                 // ...and drained by the end of the run
  // Flat: the last quarter re-fuses no more per frame than the budget allows on average.
  const size_t n = r.run.frames.size(), quarter = n / 4;
  size_t last = 0;
  for (size_t i = n - quarter; i < n; ++i) last += r.run.frames[i].reintegrated;
  EXPECT_LE(last, quarter * size_t(c.reintegration.frames_per_step + c.reintegration.frames_after_loop_per_step));
}

// Keyframe window edges (loop_closure.window_keyframes): on the busy lap every window edge joins a new keyframe to
// one 2..N keyframes before it, carries information the pose graph accepts (finite, symmetric, PSD, non-zero:
// pose_graph_edge_chi2 whitens it), the graph over the final keyframes, window edges and loops solves with finite
// poses, and the run stays a function of its input: the same trajectory bit for bit on the thread and inline.
struct WindowRun {
  SequenceRun run;
  RunSummary summary;
  std::vector<Keyframe> keyframes;
  std::vector<LoopEdge> loops, window;
  size_t window_solves = 0;
};

WindowRun run_window(bool background, int window_keyframes) {
  auto source = datasets::open_synthetic("loop", half_res("loop", kFrames));
  PipelineConfig c = busy_backend_config(background);
  c.loop_closure.window_keyframes = window_keyframes;
  Pipeline pipeline(c, source->camera());
  WindowRun out;
  out.run = run_sequence(*source, pipeline);
  out.summary = summarize(out.run, pipeline, *source, "loop");
  out.keyframes = pipeline.keyframes().all();
  out.loops = pipeline.loops();
  out.window = pipeline.window_edges();
  out.window_solves = pipeline.window_solves();
  const std::optional<double> ate = out.summary.ate_rmse_m();
  std::printf("window %d (%s): %zu window edges of %zu registered, %zu window solves, %zu loops, ATE %.2f mm\n",
              window_keyframes, background ? "thread" : "inline", out.window.size(),
              pipeline.window_registrations(), out.window_solves, out.summary.loops_closed,
              ate ? 1e3 * *ate : -1.0);
  return out;
}

TEST(Backend, WindowEdgesAreVerifiedFiniteAndTheRunStaysDeterministic) {
  constexpr int kWindow = 3;
  const WindowRun thread = run_window(true, kWindow);
  ASSERT_FALSE(thread.window.empty()) << "no window edge verified: the test proves nothing";
  EXPECT_GE(thread.window_solves + thread.summary.loops_closed, 1u);
  for (const LoopEdge& w : thread.window) {
    ASSERT_LT(w.to, thread.keyframes.size());
    EXPECT_GE(w.to - w.from, 2u);
    EXPECT_LE(w.to - w.from, size_t(kWindow));
    PoseGraphEdge e;
    e.from = w.from;
    e.to = w.to;
    e.T_from_to = w.T_from_to;
    e.information = w.information;
    double chi2 = 0.0;
    EXPECT_TRUE(pose_graph_edge_chi2(e, thread.keyframes[w.from].T_world_camera, thread.keyframes[w.to].T_world_camera,
                                     &chi2))
        << w.from << " -> " << w.to;
    EXPECT_TRUE(std::isfinite(chi2));
  }
  const PoseGraphResult res = keyframe_graph(thread.keyframes, thread.loops, thread.window).optimize();
  ASSERT_TRUE(res.ok()) << res.message;
  for (const SE3& T : res.T_world_node) EXPECT_TRUE(T.is_finite());

  const WindowRun inline_run = run_window(false, kWindow);
  ASSERT_EQ(inline_run.run.corrected.size(), thread.run.corrected.size());
  for (size_t i = 0; i < thread.run.corrected.size(); ++i)
    EXPECT_TRUE(same_bits(inline_run.run.corrected[i], thread.run.corrected[i])) << i;
  EXPECT_EQ(inline_run.window.size(), thread.window.size());
}

TEST(Backend, LoopClosureOffStartsNoBackend) {
  auto source = datasets::open_synthetic("room", half_res("room", 8));
  PipelineConfig c = busy_backend_config(true);
  c.loop_closure.enabled = false;
  Pipeline pipeline(c, source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  for (const FrameResult& f : run.frames) {
    EXPECT_FALSE(f.loop_applied);
    EXPECT_EQ(f.reintegrated, 0u);
  }
}

TEST(ReFusion, DisplacementIsTheLargestOverTheViewFrustum) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  // A pure translation moves every point by itself.
  EXPECT_NEAR(correction_displacement_m(SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.003, -0.004, 0)), cam, 3.0),
              0.005, 1e-12);
  // A rotation about the optical axis by a: a corner at distance r from the axis moves 2 r sin(a / 2).
  const double a = 0.01, z = 2.0;
  const SE3 roll(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(), Eigen::Vector3d::Zero());
  const double x = z * (-0.5 - cam.cx) / cam.fx, y = z * (-0.5 - cam.cy) / cam.fy;
  double r = std::hypot(x, y);
  for (double u : {-0.5, cam.width - 0.5})
    for (double v : {-0.5, cam.height - 0.5})
      r = std::max(r, std::hypot(z * (u - cam.cx) / cam.fx, z * (v - cam.cy) / cam.fy));
  EXPECT_NEAR(correction_displacement_m(roll, cam, z), 2.0 * r * std::sin(a / 2.0), 1e-12);
  EXPECT_EQ(correction_displacement_m(SE3(), cam, z), 0.0);
}

// Frames whose correction moves no voxel by more than half a voxel are not re-fused; a re-fused frame is never
// re-fused again for the same correction.
TEST(ReFusion, HalfAVoxelThresholdAndNeverTwice) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(3);  // 80x60
  fusion::VolumeParams vp;
  vp.voxel_m = 0.02;
  vp.capacity_blocks = 1 << 14;
  fusion::VoxelBlockGrid grid(vp);
  const DepthImage wall(cam.width, cam.height, 1.0f);
  KeyframeMap keys;
  keys.add(0, 0.0, SE3(), Matrix6d::Identity(), wall, {});
  FusedFrames fused;
  fusion::integrate(grid, wall, {}, cam, SE3());
  fused.add(0, 0, SE3(), SE3(), CompressedRgbd::encode(wall, {}, 90), 1.1);
  const auto shift = [](double m) { return SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(m, 0, 0)); };
  keys.set_pose(0, shift(0.4 * vp.voxel_m));
  fused.schedule(keys, cam, vp.voxel_m);
  EXPECT_EQ(fused.pending(), 0u) << "0.4 voxel: below half a voxel";
  keys.set_pose(0, shift(0.6 * vp.voxel_m));
  fused.schedule(keys, cam, vp.voxel_m);
  ASSERT_EQ(fused.pending(), 1u) << "0.6 voxel";
  EXPECT_EQ(fused.step(5, keys, grid, cam, {}, nullptr), 1u);
  fused.schedule(keys, cam, vp.voxel_m);
  EXPECT_EQ(fused.pending(), 0u) << "the same correction again";
  EXPECT_EQ(fused.refused(), 1u);
}

TEST(BackendThread, RunsTasksInOrderAndHandsBackTheirErrors) {
  BackendThread thread("hf-test");
  std::vector<int> order;  // written by the thread only; read after the futures
  std::vector<std::future<void>> done;
  for (int i = 0; i < 5; ++i) done.push_back(thread.submit([&order, i] { order.push_back(i); }));
  std::future<void> failing = thread.submit([] { throw std::runtime_error("job failed"); });
  for (auto& f : done) f.get();
  EXPECT_EQ(order, (std::vector<int>{0, 1, 2, 3, 4}));
  EXPECT_THROW(failing.get(), std::runtime_error);
}

}  // namespace
}  // namespace hf::slam
