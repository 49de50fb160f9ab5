// PipelineConfig::seed_on_failure (issue 34, large motion): where no registration placed a frame from the motion
// prior, sparse estimates the motion once and the dense methods retry from it. At the defaults the `fast` preset
// (15 degrees and 10 cm between frames) then tracks, and where the primary is accepted the seed never runs.
//
// The sequences are half resolution (320x240) tracked from level 0: the tracking resolution of the defaults on a
// 640x480 camera (tracking_level 1), which is what the ORB features of the seed see in a real run.
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "datasets/synthetic_source.h"
#include "slam/pipeline.h"
#include "slam/sequence_run.h"
#include "tests/slam/pipeline_test_util.h"

namespace hf::slam {
namespace {

PipelineConfig defaults_at_half_res() {
  PipelineConfig c;  // the defaults, seed_on_failure and the plausibility gate included
  c.volume.capacity_blocks = 1 << 15;
  c.tracking_level = 0;  // 320x240 frames: the defaults' tracking resolution (see above)
  return c;
}

struct PresetRun {
  SequenceRun run;
  RunSummary summary;
};

PresetRun run_seeded(const std::string& preset, int frames, const PipelineConfig& c) {
  auto source = datasets::open_synthetic(preset, test::half_res(preset, frames));
  Pipeline pipeline(c, source->camera());
  PresetRun r;
  r.run = run_sequence(*source, pipeline);
  r.summary = summarize(r.run, pipeline, *source, "synthetic:" + preset);
  std::printf("%s, seed_on_failure '%s': %ld of %zu frames lost, %ld seeded (%ld placed by the retry), ATE %.4f m\n",
              preset.c_str(), c.seed_on_failure.c_str(), r.summary.frames_lost, r.run.frames.size(),
              r.summary.frames_seeded_on_failure, r.summary.frames_placed_by_seed,
              r.summary.ate_rmse_m().value_or(-1.0));
  return r;
}

// 12 frames = 11 motions of 15 degrees. Without the seed the dense methods lose almost all of them (the first
// motion starts from the identity, and every lost frame leaves the next one farther from the reference); with it
// each frame is placed. The ATE bound: combined started from sparse reaches 2.4 mm over 60 frames at this
// tracking resolution (bench/results/sparse.md), and the target is 1 cm; 1 cm is kept as the bound.
TEST(SeedOnFailure, FastPresetTracksAtTheDefaults) {
  PipelineConfig off = defaults_at_half_res();
  off.seed_on_failure.clear();
  const PresetRun without = run_seeded("fast", 12, off);
  EXPECT_GE(without.summary.frames_lost, 8);
  EXPECT_EQ(without.summary.frames_seeded_on_failure, 0);

  const PresetRun with = run_seeded("fast", 12, defaults_at_half_res());
  EXPECT_LE(with.summary.frames_lost, 1);
  ASSERT_TRUE(with.summary.ate_rmse_m());
  EXPECT_LT(*with.summary.ate_rmse_m(), 0.01);
  // The seed runs where the prior fails (at least the first motion, from the identity), not on every frame: once
  // the constant-velocity prior holds the last motion, the dense method converges from it by itself.
  EXPECT_GE(with.summary.frames_seeded_on_failure, 1);
  EXPECT_GE(with.summary.frames_placed_by_seed, 1);
  EXPECT_LT(with.summary.frames_seeded_on_failure, 6);
  for (const FrameResult& f : with.run.frames) {
    if (f.placed_by_seed) {
      EXPECT_TRUE(f.seeded_on_failure) << "frame " << f.index;
      EXPECT_TRUE(f.pose_valid) << "frame " << f.index;
    }
  }
}

// Where the motion is small the primary places every frame from the motion prior: the seed never runs there. It
// runs on the one frame without a prior (the second: wide_basin_without_prior's cross-check, tests/slam/
// test_wide_basin.cpp); with that off too, the trajectory is the one without the seed, bit for bit.
TEST(SeedOnFailure, NeverRunsWhereThePrimaryIsAccepted) {
  PipelineConfig off = defaults_at_half_res();
  off.seed_on_failure.clear();
  off.wide_basin_without_prior = false;
  PipelineConfig on = defaults_at_half_res();
  on.wide_basin_without_prior = false;
  const PresetRun without = run_seeded("room", 8, off);
  const PresetRun with = run_seeded("room", 8, on);
  EXPECT_EQ(with.summary.frames_lost, 0);
  EXPECT_EQ(with.summary.frames_seeded_on_failure, 0);
  ASSERT_EQ(with.run.frames.size(), without.run.frames.size());
  for (size_t i = 0; i < with.run.frames.size(); ++i) {
    const FrameResult& f = with.run.frames[i];
    EXPECT_FALSE(f.seeded_on_failure) << "frame " << f.index;
    EXPECT_EQ(f.state, without.run.frames[i].state) << "frame " << f.index;
    EXPECT_TRUE(f.T_world_camera.matrix() == without.run.frames[i].T_world_camera.matrix())
        << "frame " << f.index;
  }
  // At the defaults: only the frame without a prior.
  const PresetRun defaults = run_seeded("room", 8, defaults_at_half_res());
  EXPECT_EQ(defaults.summary.frames_lost, 0);
  for (const FrameResult& f : defaults.run.frames) {
    EXPECT_EQ(f.seeded_on_failure, f.wide_basin) << "frame " << f.index;
    EXPECT_EQ(f.wide_basin, f.index == 1) << "frame " << f.index;
  }
}

TEST(SeedOnFailure, ConfigReadsWritesAndValidatesIt) {
  PipelineConfig c;
  EXPECT_EQ(c.seed_on_failure, "sparse");  // the default
  c.seed_on_failure = "";
  EXPECT_EQ(config_from_json(config_to_json(c), "test").seed_on_failure, "");
  EXPECT_EQ(config_from_json(nlohmann::json{{"seed_on_failure", "icp"}}, "test").seed_on_failure, "icp");
  c.seed_on_failure = "nope";
  EXPECT_THROW(c.validate(), Error);
  EXPECT_THROW(config_from_json(nlohmann::json{{"seed_on_failure", 3}}, "test"), Error);
}

}  // namespace
}  // namespace hf::slam
