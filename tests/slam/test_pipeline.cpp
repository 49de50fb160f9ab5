// The SLAM pipeline end to end on short synthetic sequences (half resolution, so each test takes seconds): tracking
// accuracy, the map against the analytic scene, the failure policy (garbage frames are lost, never integrated, and
// tracking recovers), the configuration's JSON form, and no NaN pose on any hard case.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <algorithm>
#include <cstdio>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <vector>

#include "core/error.h"
#include "datasets/synthetic_source.h"
#include "registration/combined.h"
#include "registration/icp.h"
#include "slam/pipeline.h"
#include "tests/slam/pipeline_test_util.h"
#include "slam/sequence_run.h"
#include "tests/common/sanitizer.h"

namespace hf::slam {
namespace {

using test::ModifiedSource;

using test::half_res;

PipelineConfig config_for(const std::string& registration) {
  PipelineConfig c;
  c.registration = registration;
  c.volume.capacity_blocks = 1 << 15;
  return c;
}

bool finite_pose(const SE3& T) { return T.matrix().allFinite(); }

TEST(Pipeline, CombinedTracksRoomWithinOneCentimetre) {
  // Issue 5: `room` with `combined` reaches ATE < 1 cm over 60 frames (Kinect-like noise).
  auto source = datasets::open_synthetic("room", half_res("room", 60));
  Pipeline pipeline(config_for("combined"), source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  ASSERT_EQ(run.frames.size(), 60u);
  const RunSummary s = summarize(run, pipeline, *source, "synthetic:room");
  EXPECT_EQ(s.frames_lost, 0);
  ASSERT_TRUE(s.ate_rmse_m());
  EXPECT_LT(*s.ate_rmse_m(), 0.01);
  EXPECT_GT(s.blocks_allocated, 0u);
  EXPECT_GT(s.mean_ms.track, 0.0);
  EXPECT_GT(s.mean_ms.raycast, 0.0);
  EXPECT_EQ(run.frames[0].state, TrackState::initialised);
  for (size_t i = 1; i < run.frames.size(); ++i) EXPECT_EQ(run.frames[i].state, TrackState::tracked) << i;
}

// Issue 16's corridor through the pipeline as the harness runs it (640x480 frames, tracking from 320x240, 30
// frames, seed 1, colour check off). The target: combined within 1.5x of the best single method, photometric
// (1.73 mm measured). With one photometric regime (CombinedOptions::clean_scale_rgb 0: the defaults before the
// regimes, Student-t nu 10 floored at 0.02) the corridor's few large photometric residuals (its far, barely fused
// walls) keep full weight and icp's biased weak-direction information drags the estimate: 5.04 mm measured. The
// corridor's images agree with the model to ~1.5 grey levels (its scales' median 0.006), so the defaults switch to
// the clean regime after five frames: 2.31 mm measured (1.34x). Bounds: the issue's 1.5x, and 60 % of one regime's.
TEST(Pipeline, CombinedCorridorWithinOneAndAHalfOfPhotometric) {
  HF_RELEASE_ONLY_ACCURACY("Pipeline.CombinedTracksRoomWithinOneCentimetre and CombinedPhotometricRegimeFollowsTheImages");
  std::optional<double> ate[3];  // one regime, defaults, photometric
  for (int run_index : {0, 1, 2}) {
    datasets::SyntheticOptions o = half_res("corridor", 30);
    o.camera = PinholeCamera::preset("ros");
    o.seed = 1;
    auto source = datasets::open_synthetic("corridor", o);
    const std::string method = run_index == 2 ? "photometric" : "combined";
    PipelineConfig c = config_for(method);
    c.tracking_level = 1;
    c.colour_check.enabled = false;
    RegistrationOptions r = pipeline_registration_options(method);
    if (run_index == 0) r.method_as<CombinedOptions>().clean_scale_rgb = 0.0f;
    c.registration_options = r;
    Pipeline pipeline(c, source->camera());
    const SequenceRun run = run_sequence(*source, pipeline);
    const RunSummary s = summarize(run, pipeline, *source, "synthetic:corridor");
    EXPECT_EQ(s.frames_lost, 0);
    ate[run_index] = s.ate_rmse_m();
    ASSERT_TRUE(ate[run_index]);
    std::printf("corridor: %s ATE %.2f mm\n", run_index == 0 ? "combined, one regime" : method.c_str(),
                *ate[run_index] * 1e3);
  }
  EXPECT_LE(*ate[1], 1.5 * *ate[2]);
  EXPECT_LT(*ate[1], 0.6 * *ate[0]);
}

// The photometric regime follows the images: a room whose colour carries 10 grey levels of noise per channel (a
// real camera's scale, above clean_scale_rgb) never leaves the default regime, so its trajectory is the one
// regime's bit for bit; the same room with the preset's 2 grey levels is clean and its trajectory departs from the
// one regime's once scale_history_min (5) registrations are in.
TEST(Pipeline, CombinedPhotometricRegimeFollowsTheImages) {
  for (double colour_sigma : {10.0, 2.0}) {
    std::vector<SE3> poses[2];
    for (int regimes : {0, 1}) {
      datasets::SyntheticOptions o = half_res("room", 12);
      datasets::NoiseOptions noise;
      noise.colour_sigma = colour_sigma;
      o.noise = noise;
      auto source = datasets::open_synthetic("room", o);
      PipelineConfig c = config_for("combined");
      c.colour_check.enabled = false;
      RegistrationOptions r = pipeline_registration_options("combined");
      if (!regimes) r.method_as<CombinedOptions>().clean_scale_rgb = 0.0f;
      c.registration_options = r;
      Pipeline pipeline(c, source->camera());
      const SequenceRun run = run_sequence(*source, pipeline);
      ASSERT_EQ(run.frames.size(), 12u);
      for (const auto& f : run.frames) poses[regimes].push_back(f.T_world_camera);
    }
    bool same = true;
    for (size_t i = 0; i < poses[0].size(); ++i) same = same && poses[0][i].matrix() == poses[1][i].matrix();
    if (colour_sigma > 5.0) {
      EXPECT_TRUE(same) << "a noisy camera's sequence left the default regime";
    } else {
      EXPECT_FALSE(same) << "a clean sequence stayed in the default regime";
      for (size_t i = 0; i <= 5; ++i)  // the first registrations precede the switch
        EXPECT_EQ(poses[0][i].matrix(), poses[1][i].matrix()) << i;
    }
  }
}

// `sdf` aligns each frame to the TSDF itself (Registration::aligns_to_volume), so the pipeline skips the tracking
// raycast and checks depth agreement against the volume: the room still tracks within a centimetre, every frame
// tracked (60 frames, Kinect-like noise, the bound of combined's test above).
TEST(Pipeline, SdfTracksRoomWithoutATrackingRaycast) {
  auto source = datasets::open_synthetic("room", half_res("room", 60));
  Pipeline pipeline(config_for("sdf"), source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  ASSERT_EQ(run.frames.size(), 60u);
  const RunSummary s = summarize(run, pipeline, *source, "synthetic:room");
  EXPECT_EQ(s.frames_lost, 0);
  ASSERT_TRUE(s.ate_rmse_m());
  EXPECT_LT(*s.ate_rmse_m(), 0.01);
  for (size_t i = 1; i < run.frames.size(); ++i) EXPECT_EQ(run.frames[i].state, TrackState::tracked) << i;
}

// PipelineConfig::model_hint: where the frame has no depth (the `holes` preset drops blobs of it), the tracking
// raycast searches from the last model raycast's depth instead of marching the whole ray. Where both find a
// surface it is the same one, refined to 0.05 voxel, so tracking must be as good either way: no frame lost, and the
// ATE no worse than a tenth of a voxel (1 mm) above the full march's (measured over 20 frames: 0.73 mm with the
// hint, 0.75 mm without).
TEST(Pipeline, ModelHintTracksHolesAsWellAsTheFullMarch) {
  std::optional<double> ate[2];
  for (int on = 0; on < 2; ++on) {
    auto source = datasets::open_synthetic("holes", half_res("holes", 20));
    PipelineConfig c = config_for("combined");
    c.model_hint = on != 0;
    Pipeline pipeline(c, source->camera());
    const SequenceRun run = run_sequence(*source, pipeline);
    const RunSummary s = summarize(run, pipeline, *source, "synthetic:holes");
    EXPECT_EQ(s.frames_lost, 0) << "model_hint " << on;
    ate[on] = s.ate_rmse_m();
    ASSERT_TRUE(ate[on]);
    EXPECT_LT(*ate[on], 0.01) << "model_hint " << on;
  }
  EXPECT_LE(*ate[1], *ate[0] + 0.001);
}

// Issue 19: with a quarter of the finest level's rows (importance-driven, GaussNewtonOptions::row_selection) and
// the tracking raycast cast only at those pixels grown by 2 (tracking_raycast "sampled"), `room` still tracks
// within the 1 cm of CombinedTracksRoomWithinOneCentimetre, every frame; the config keys survive JSON.
TEST(Pipeline, SelectedRowsAndSampledRaycastTrackRoomWithinOneCentimetre) {
  auto source = datasets::open_synthetic("room", half_res("room", 15));
  PipelineConfig c = config_for("combined");
  RegistrationOptions r = pipeline_registration_options("combined");
  ASSERT_TRUE(r.set("row_selection", 1));
  ASSERT_TRUE(r.set("row_selection_budget", 64));
  ASSERT_TRUE(r.set("finest_level_photometric_step", 1));
  c.registration_options = r;
  c.tracking_raycast = "sampled";
  Pipeline pipeline(c, source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  const RunSummary s = summarize(run, pipeline, *source, "synthetic:room");
  EXPECT_EQ(s.frames_lost, 0);
  ASSERT_TRUE(s.ate_rmse_m());
  EXPECT_LT(*s.ate_rmse_m(), 0.01);
  for (size_t i = 1; i < run.frames.size(); ++i) EXPECT_EQ(run.frames[i].state, TrackState::tracked) << i;

  const PipelineConfig back = config_from_json(config_to_json(c), "test");
  EXPECT_EQ(back.tracking_raycast, "sampled");
  EXPECT_EQ(back.registration_options->driver.row_selection.mode, PixelSelectionMode::importance);
  EXPECT_EQ(back.registration_options->driver.row_selection.budget_per_tile, 64);
  c.tracking_raycast = "sparse";
  EXPECT_THROW(c.validate(), Error);
}

TEST(Pipeline, GroundTruthMapMatchesTheScene) {
  // Fusion only, noise-free depth, against the analytic scene. The fusion issue's sphere bounds (RMS <= 0.2 voxel,
  // max <= 1 voxel) hold on smooth surfaces; the room also has convex box edges and concave wall corners, which a
  // TSDF rounds off by construction (two surfaces inside one truncation band; measured tail up to ~1.8 voxels at
  // both 320x240 and 640x480, so it is not a sampling effect). So: the smooth bulk (95th percentile) within 0.2
  // voxel, 99% of vertices within 1 voxel, and the RMS (which the edge tail dominates) within 0.3 voxel.
  auto opts = half_res("room", 20);
  opts.noise_enabled = false;
  datasets::SyntheticSequence seq(opts);
  auto source = datasets::open_synthetic("room", opts);
  PipelineConfig c = config_for("groundtruth");
  Pipeline pipeline(c, source->camera());
  const SequenceRun run = run_sequence(*source, pipeline);
  for (const auto& f : run.frames) EXPECT_EQ(f.state, TrackState::groundtruth);
  const TriangleMesh mesh = pipeline.extract_mesh();
  ASSERT_GT(mesh.vertices.size(), 1000u);
  double sum2 = 0.0;
  std::vector<double> abs_d;
  for (const auto& v : mesh.vertices) {
    const double d = seq.scene().sdf(v.cast<double>());
    sum2 += d * d;
    abs_d.push_back(std::abs(d));
  }
  const double rms_vox = std::sqrt(sum2 / double(mesh.vertices.size())) / c.volume.voxel_m;
  std::sort(abs_d.begin(), abs_d.end());
  const double p99_vox = abs_d[abs_d.size() * 99 / 100] / c.volume.voxel_m;
  const double p95_vox = abs_d[abs_d.size() * 95 / 100] / c.volume.voxel_m;
  std::printf("mesh vs scene: rms %.3f, 95%% %.3f, 99%% %.3f voxel\n", rms_vox, p95_vox, p99_vox);
  EXPECT_LE(p95_vox, 0.2);
  EXPECT_LE(p99_vox, 1.0);
  EXPECT_LE(rms_vox, 0.3);
}

TEST(Pipeline, GarbageFramesAreLostNotIntegratedAndTrackingRecovers) {
  // Frame 12: uniform random depth (a sensor glitch); frame 20: no depth at all. Neither may touch the map; frame
  // 12's colour still tracks (the pose keeps moving: odometry) or it is lost; frame 20 has nothing to track with and
  // is lost; tracking continues right after each.
  auto inner = datasets::open_synthetic("room", half_res("room", 40));
  ModifiedSource source(std::move(inner), [](RgbdFrame& f) {
    if (f.index == 12) {
      std::mt19937 rng(7);
      std::uniform_real_distribution<float> depth(0.3f, 5.0f);
      for (int y = 0; y < f.depth.height(); ++y)
        for (int x = 0; x < f.depth.width(); ++x) f.depth(x, y) = depth(rng);
    } else if (f.index == 20) {
      f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);
    }
  });
  Pipeline pipeline(config_for("combined"), source.camera());
  size_t blocks_before_glitch = 0;
  RunControl control;
  control.on_frame = [&](const FrameResult& r) {
    if (r.index == 11) blocks_before_glitch = pipeline.map().block_count();
    if (r.index == 12) {
      EXPECT_EQ(pipeline.map().block_count(), blocks_before_glitch);
    }
  };
  const SequenceRun run = run_sequence(source, pipeline, control);
  ASSERT_EQ(run.frames.size(), 40u);
  for (const auto& f : run.frames) EXPECT_TRUE(finite_pose(f.T_world_camera)) << f.index;
  const TrackState s12 = run.frames[12].state;
  EXPECT_TRUE(s12 == TrackState::lost || s12 == TrackState::odometry) << to_string(s12);
  EXPECT_FALSE(run.frames[12].integrated);
  EXPECT_EQ(run.frames[12].pose_valid, s12 == TrackState::odometry);
  EXPECT_FALSE(run.frames[12].message.empty());
  EXPECT_EQ(run.frames[20].state, TrackState::lost);
  EXPECT_FALSE(run.frames[20].integrated);
  EXPECT_FALSE(run.frames[20].pose_valid);
  EXPECT_EQ(run.frames[13].state, s12 == TrackState::lost ? TrackState::recovered : TrackState::tracked);
  EXPECT_EQ(run.frames[21].state, TrackState::recovered);
  for (size_t i = 0; i < run.frames.size(); ++i) {
    if (i == 12 || i == 20) continue;
    EXPECT_TRUE(run.frames[i].integrated) << i;
  }
  const RunSummary s = summarize(run, pipeline, source, "injected");
  ASSERT_TRUE(s.ate_rmse_m());
  EXPECT_LT(*s.ate_rmse_m(), 0.01);  // over all 40 frames, the lost ones at their reported pose
  EXPECT_EQ(s.frames_lost, run.frames_lost());
  EXPECT_EQ(s.lost_spells, s.frames_lost);  // each fault is a spell of one frame
  EXPECT_EQ(s.longest_lost_spell, 1);
  EXPECT_NEAR(s.coverage, double(40 - s.frames_lost) / 40.0, 1e-12);
}

TEST(Pipeline, FirstFramesWithoutDepthDoNotInitialise) {
  auto inner = datasets::open_synthetic("room", half_res("room", 8));
  ModifiedSource source(std::move(inner), [](RgbdFrame& f) {
    if (f.index < 2) f.depth = DepthImage(f.depth.width(), f.depth.height(), 0.0f);
  });
  Pipeline pipeline(config_for("icp"), source.camera());
  const SequenceRun run = run_sequence(source, pipeline);
  ASSERT_EQ(run.frames.size(), 8u);
  EXPECT_EQ(run.frames[0].state, TrackState::lost);
  EXPECT_EQ(run.frames[1].state, TrackState::lost);
  EXPECT_FALSE(run.frames[0].integrated);  // reported honestly (issue 14): nothing was fused
  EXPECT_FALSE(run.frames[1].integrated);
  EXPECT_EQ(run.frames[2].state, TrackState::initialised);
  EXPECT_EQ(run.frames[3].state, TrackState::tracked);
}

TEST(Pipeline, EveryHardCaseGivesFinitePosesAndReportsItsFrames) {
  for (const std::string preset : {"wall", "corridor", "textureless", "fast", "holes", "exposure"}) {
    SCOPED_TRACE(preset);
    auto source = datasets::open_synthetic(preset, half_res(preset, 10));
    Pipeline pipeline(config_for("combined"), source->camera());
    const SequenceRun run = run_sequence(*source, pipeline);
    ASSERT_EQ(run.frames.size(), 10u);
    long lost = 0;
    for (const auto& f : run.frames) {
      EXPECT_TRUE(finite_pose(f.T_world_camera)) << f.index;
      if (f.state == TrackState::lost) {
        ++lost;
        EXPECT_FALSE(f.message.empty());
        EXPECT_FALSE(f.integrated);
      }
    }
    const RunSummary s = summarize(run, pipeline, *source, preset);
    EXPECT_EQ(s.frames_lost, lost);
    const nlohmann::json j = summary_to_json(s, run, pipeline, *source);
    EXPECT_EQ(j["frames_lost"].get<long>(), lost);
  }
}

TEST(Pipeline, WrongFrameSizeIsAnError) {
  const PinholeCamera cam = PinholeCamera::preset("ros").scaled(1);
  Pipeline pipeline(config_for("icp"), cam);
  RgbdFrame f;
  f.depth = DepthImage(100, 80, 1.0f);
  f.depth_file = "depth/1.png";
  try {
    pipeline.process(f);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("depth/1.png"), std::string::npos) << e.what();
  }
}

TEST(PipelineConfig, JsonRoundTripAndErrors) {
  PipelineConfig c = config_for("icp");
  c.volume.voxel_m = 0.02;
  c.max_speed_m_per_s = 1.5;
  RegistrationOptions r = default_registration_options("icp");
  r.driver.iterations = {6, 4, 2};
  r.method_as<IcpOptions>().robust_icp = RobustKernel::student_t;
  c.registration_options = r;
  const nlohmann::json j = config_to_json(c);
  const PipelineConfig back = config_from_json(j, "test");
  EXPECT_EQ(config_to_json(back), j);
  EXPECT_EQ(back.volume.voxel_m, 0.02);
  ASSERT_TRUE(back.registration_options);
  EXPECT_EQ(back.registration_options->driver.iterations, (std::vector<int>{6, 4, 2}));
  EXPECT_EQ(back.registration_options->method_as<IcpOptions>().robust_icp, RobustKernel::student_t);

  auto error_of = [](const nlohmann::json& bad) -> std::string {
    try {
      config_from_json(bad, "cfg.json");
    } catch (const Error& e) {
      return e.what();
    }
    return "";
  };
  EXPECT_NE(error_of({{"voxel", 0.01}}).find("cfg.json: unknown key 'voxel'"), std::string::npos);
  EXPECT_NE(error_of({{"volume", {{"voxel_m", "big"}}}}).find("voxel_m: expected a number"), std::string::npos);
  EXPECT_NE(error_of({{"volume", {{"voxel_m", -1.0}}}}).find("cfg.json"), std::string::npos);
  EXPECT_NE(error_of({{"registration", "nope"}}).find("cfg.json: unknown registration method 'nope'"),
            std::string::npos);
  EXPECT_NE(error_of({{"constant_velocity", 3}}).find("cfg.json: constant_velocity: expected true or false"),
            std::string::npos);
  const std::string capacity = error_of({{"volume", {{"capacity_blocks", -5}}}});
  EXPECT_NE(capacity.find("cfg.json: volume.capacity_blocks: expected an integer, got one out of range"),
            std::string::npos) << capacity;
  EXPECT_EQ(capacity.find("18446744073709551615"), std::string::npos) << capacity;
  EXPECT_NE(error_of({{"registration_options", {{"robust_icp", "cauchy"}}}}).find("unknown robust kernel"),
            std::string::npos);
  // Issue 35: an unknown method beside registration_options (a report.json's config) names the file too, and a
  // voxel no sensor resolves is refused instead of losing every frame to a full pool.
  const std::string bogus = error_of({{"registration", "bogus"}, {"registration_options", nlohmann::json::object()}});
  EXPECT_EQ(bogus.rfind("cfg.json: ", 0), 0u) << bogus;
  EXPECT_NE(bogus.find("bogus"), std::string::npos) << bogus;
  EXPECT_NE(error_of({{"volume", {{"voxel_m", 1e-9}}}}).find("volume.voxel_m: expected 0.0001..10 m, got 1e-09"),
            std::string::npos) << error_of({{"volume", {{"voxel_m", 1e-9}}}});
}

TEST(PipelineConfig, FileErrorsNameFileAndLine) {
  const auto dir = std::filesystem::temp_directory_path() / "hf_test_pipeline_config";
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "bad.json").string();
  {
    std::ofstream out(path);
    out << "{\n  \"registration\": \"icp\",\n  \"volume\": { \"voxel_m\": 0.01,, }\n}\n";
  }
  try {
    load_config(path);
    FAIL() << "expected a parse error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path + ":3:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_config((dir / "missing.json").string()), Error);
}

// rgb_weight has one home (registration_options); the former top-level key still reads, into it, and the
// pipeline's default differs from combined's own (kPipelineRgbWeight).
TEST(PipelineConfig, RgbWeightHasOneHome) {
  const nlohmann::json defaults = config_to_json(PipelineConfig{});
  EXPECT_FALSE(defaults.contains("rgb_weight"));
  EXPECT_FLOAT_EQ(defaults["registration_options"]["rgb_weight"].get<float>(), float(kPipelineRgbWeight));
  const PipelineConfig former = config_from_json({{"registration", "combined"}, {"rgb_weight", 0.25}}, "old.json");
  EXPECT_FLOAT_EQ(config_to_json(former)["registration_options"]["rgb_weight"].get<float>(), 0.25f);
  // The section's own value wins over the former top-level one.
  const PipelineConfig both = config_from_json(
      {{"rgb_weight", 0.25}, {"registration_options", {{"rgb_weight", 0.6}}}}, "old.json");
  EXPECT_FLOAT_EQ(config_to_json(both)["registration_options"]["rgb_weight"].get<float>(), 0.6f);
  EXPECT_THROW(config_from_json({{"rgb_weight", -1.0}}, "old.json"), Error);
  EXPECT_THROW(config_from_json({{"rgb_weight", "a lot"}}, "old.json"), Error);
  // icp has no such knob: the former key is accepted and has nothing to set.
  EXPECT_FALSE(config_to_json(config_from_json({{"registration", "icp"}, {"rgb_weight", 0.25}}, "old.json"))
                   ["registration_options"].contains("rgb_weight"));
}

// pyramid.levels is the depth registration runs at: the method's own counts cut to it (combined's registry default
// has five, for guess-free pairs), never lengthened (a count may be a method's own resolution, as NDT's); a count
// list given in registration_options is kept as written.
TEST(PipelineConfig, TrackingLevelsFollowThePyramid) {
  auto iterations = [](const nlohmann::json& j) {
    return effective_registration_options(config_from_json(j, "c.json")).driver.iterations;
  };
  EXPECT_EQ(iterations({{"registration", "combined"}}), (std::vector<int>{10, 5, 4}));
  EXPECT_EQ(iterations({{"registration", "combined"}, {"pyramid", {{"levels", 4}}}}),
            (std::vector<int>{10, 5, 4, 4}));
  EXPECT_EQ(iterations({{"registration", "combined"}, {"pyramid", {{"levels", 2}}}}), (std::vector<int>{10, 5}));
  EXPECT_EQ(iterations({{"registration", "icp"}, {"pyramid", {{"levels", 5}}}}), (std::vector<int>{10, 5, 4}));
  EXPECT_EQ(iterations({{"registration", "combined"},
                        {"pyramid", {{"levels", 4}}},
                        {"registration_options", {{"iterations", {8, 4}}}}}),
            (std::vector<int>{8, 4}));
  // The hand-over tracker's options follow the same pyramid.
  const PipelineConfig c = config_from_json(
      {{"pyramid", {{"levels", 2}}}, {"depth_only_registration_options", {{"huber_sdf_m", 0.005}}}}, "c.json");
  ASSERT_TRUE(c.depth_only_registration_options);
  EXPECT_EQ(c.depth_only_registration_options->driver.iterations, (std::vector<int>{20, 10}));
}

// report.json files written before methods owned their knobs keep reading: their registration_options hold every
// method's keys (the former RegistrationOptions' visitor, all defaults but t_dof 7 and max_dist_m 0.2), which each
// method renames or drops by registration's rule (migrate_registration_key).
TEST(PipelineConfig, FormerRegistrationOptionsStillRead) {
  const nlohmann::json former = nlohmann::json::parse(R"({"iterations": [10, 5, 4], "min_step_rotation_rad": 1e-05,
      "min_step_translation_m": 1e-05, "max_dist_m": 0.2, "max_normal_angle_deg": 30.0, "robust_icp": "huber",
      "huber_icp_m": 0.01, "robust_rgb": "huber", "huber_rgb": 0.05, "t_dof": 7.0, "t_sigma_rgb_init": 0.05,
      "t_sigma_rgb_min": 0.002, "t_sigma_icp_m": 0.01, "rgb_weight": 0.4, "min_gradient": 0.0039215689,
      "photometric_occlusion_check": true, "degeneracy_threshold": 0.003, "min_inliers": 64, "poor_inlier_ratio": 0.3,
      "max_translation_m": 0.5, "max_rotation_deg": 45.0, "max_final_step_translation_m": 0.002,
      "max_final_step_rotation_rad": 0.002})");
  for (const std::string method : {"icp", "photometric", "combined", "groundtruth"}) {
    SCOPED_TRACE(method);
    const PipelineConfig c =
        config_from_json({{"registration", method}, {"registration_options", former}}, "report.json");
    ASSERT_TRUE(c.registration_options);
    EXPECT_EQ(c.registration_options->driver.iterations, (std::vector<int>{10, 5, 4}));
    nlohmann::json now = config_to_json(c)["registration_options"];
    if (method == "icp") {
      EXPECT_FLOAT_EQ(now["max_dist_m"].get<float>(), 0.2f);
      EXPECT_FLOAT_EQ(now["t_dof_icp"].get<float>(), 7.0f);
      EXPECT_FALSE(now.contains("rgb_weight"));
    } else if (method == "photometric") {
      EXPECT_FLOAT_EQ(now["occlusion_max_depth_m"].get<float>(), 0.2f);
      EXPECT_FLOAT_EQ(now["t_dof"].get<float>(), 7.0f);
      EXPECT_EQ(now["robust_rgb"], "huber");
      EXPECT_FALSE(now.contains("max_dist_m"));
    } else if (method == "combined") {
      EXPECT_FLOAT_EQ(now["max_dist_m"].get<float>(), 0.2f);
      EXPECT_FLOAT_EQ(now["t_dof"].get<float>(), 7.0f);
      EXPECT_FLOAT_EQ(now["rgb_weight"].get<float>(), 0.4f);
    } else {
      EXPECT_FALSE(now.contains("max_dist_m"));
    }
    // A key that was never a registration option is still a mistake.
    nlohmann::json typo = former;
    typo["max_dist"] = 0.1;
    EXPECT_THROW(config_from_json({{"registration", method}, {"registration_options", typo}}, "report.json"), Error);
  }
}

}  // namespace
}  // namespace hf::slam
