// Tracking that recovers and stays consistent (issue 13), on synthetic sequences with exact ground truth:
// relocalisation after a kidnap, loop closure on the pose graph with the map re-fused from the corrected poses,
// and `--global`'s final optimisation.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "datasets/presets.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/synthetic_source.h"
#include "slam/pipeline.h"
#include "tests/slam/pipeline_test_util.h"
#include "slam/sequence_run.h"

namespace hf::slam {
namespace {

using test::half_res;

PipelineConfig default_config() {
  PipelineConfig c;
  c.volume.capacity_blocks = 1 << 16;
  return c;
}

double translation_error_m(const SE3& a, const SE3& b) { return (a.translation() - b.translation()).norm(); }

// The camera jumps at frame 75 back to frame 0's viewpoint, 0.7 m and ~30 degrees away: tracking cannot follow, the
// keyframe of frame 0 is where the frame is, and relocalisation must put it there within 5 frames. No frame may be
// integrated at a wrong pose.
TEST(SlamRecovery, KidnappedCameraIsRelocalisedWithinFiveFrames) {
  constexpr int kJump = 75, kFrames = 95;
  auto source = datasets::open_synthetic("kidnap", half_res("kidnap", kFrames));
  const datasets::Preset preset = datasets::make_preset("kidnap");
  ASSERT_GT(translation_error_m(preset.T_world_camera(kJump - 1), preset.T_world_camera(kJump)), 0.5);
  Pipeline pipeline(default_config(), source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  ASSERT_EQ(run.frames.size(), size_t(kFrames));
  int back = -1;
  for (int i = kJump; i < kFrames && back < 0; ++i)
    if (run.frames[size_t(i)].pose_valid &&
        translation_error_m(run.frames[size_t(i)].T_world_camera, preset.T_world_camera(i)) < 0.02)
      back = i;
  ASSERT_GE(back, kJump) << "never relocalised";
  EXPECT_LE(back - kJump, 5);
  for (const FrameResult& f : run.frames) {
    if (!f.integrated) continue;
    EXPECT_LT(translation_error_m(f.T_world_camera, preset.T_world_camera(int(f.index))), 0.02)
        << "frame " << f.index << " integrated at a wrong pose (" << to_string(f.state) << ")";
  }
  const RunSummary s = summarize(run, pipeline, *source, "kidnap");
  EXPECT_GE(s.frames_relocalised, 1);
  EXPECT_LE(s.frames_lost, 5);
}

struct LoopRun {
  double ate_m = 0.0, mesh_rms_m = 0.0;
  size_t loops = 0;
};

LoopRun run_loop(bool loop_closure, bool global) {
  constexpr int kFrames = 250;  // one lap (240 frames) and a little more
  // At the benchmark's input size (640x480, tracked at 320x240). At half that size the remaining error is
  // dominated by a scale bias of the tracking (0.8 %, which no loop removes; 0.35 % at 640x480), and the ratio
  // sits at the target itself (9.9 -> 5.0 mm).
  datasets::SyntheticOptions o;
  o.preset = "loop";
  o.frames = kFrames;
  auto source = datasets::open_synthetic("loop", o);
  PipelineConfig c = default_config();
  c.loop_closure.enabled = loop_closure;
  Pipeline pipeline(c, source->camera());
  RunControl control;
  control.global = global;
  const SequenceRun run = run_sequence(*source, pipeline, control);
  const RunSummary s = summarize(run, pipeline, *source, "loop");
  LoopRun out;
  out.ate_m = s.ate_rmse_m().value_or(1e9);
  out.loops = s.loops_closed;
  const datasets::Preset preset = datasets::make_preset("loop");
  const TriangleMesh mesh = pipeline.extract_mesh();
  double sum2 = 0.0;
  for (const auto& v : mesh.vertices) {
    const double d = preset.scene.sdf(v.cast<double>());
    sum2 += d * d;
  }
  out.mesh_rms_m = mesh.vertices.empty() ? 1e9 : std::sqrt(sum2 / double(mesh.vertices.size()));
  std::printf("loop closure %s%s: ATE %.2f mm, mesh RMS %.2f mm, %zu loops, %ld lost\n", loop_closure ? "on" : "off",
              global ? " + global" : "", out.ate_m * 1e3, out.mesh_rms_m * 1e3, out.loops, s.frames_lost);
  return out;
}

// One outward-looking lap of the room: tracking drifts until the first walls come back. Closing the loop on the
// keyframe graph must halve the trajectory error (the target), and the re-fused map must lie closer to
// the scene. The graph's odometry edges are keyframe-to-keyframe registrations, independent of the map: the
// tracked poses snap back onto the first walls as they come into view, which hides the drift from a loop edge.
TEST(SlamRecovery, LoopClosureLowersTheErrorOfALap) {
  const LoopRun off = run_loop(false, false);
  const LoopRun on = run_loop(true, false);
  EXPECT_EQ(off.loops, 0u);
  EXPECT_GE(on.loops, 1u);
  EXPECT_LE(on.ate_m, 0.5 * off.ate_m);
  EXPECT_LT(on.mesh_rms_m, off.mesh_rms_m);
  const LoopRun global = run_loop(true, true);
  EXPECT_LE(global.ate_m, 0.5 * off.ate_m);
  EXPECT_LT(global.mesh_rms_m, off.mesh_rms_m);
}

}  // namespace
}  // namespace hf::slam
