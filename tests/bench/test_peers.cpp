// The PCL peer runner: back-projection, and GICP / NDT frame-to-frame odometry on a short synthetic room.
#include <gtest/gtest.h>

#include "bench/harness/peers.h"
#include "core/error.h"
#include "datasets/synthetic_source.h"
#include "slam/eval.h"

namespace hf::bench {
namespace {

TEST(BenchPeers, BackprojectDepth) {
  PinholeCamera cam;
  cam.fx = cam.fy = 2.0;
  cam.cx = cam.cy = 1.5;
  cam.width = cam.height = 4;
  DepthImage depth(4, 4);
  depth(0, 0) = 1.0f;
  depth(2, 2) = 2.0f;
  depth(3, 3) = 3.0f;           // odd pixel: skipped with stride 2
  depth(2, 0) = NAN;            // invalid: skipped
  const auto all = backproject_depth(depth, cam, 1);
  ASSERT_EQ(all.size(), 3u);
  const auto strided = backproject_depth(depth, cam, 2);
  ASSERT_EQ(strided.size(), 2u);
  EXPECT_FLOAT_EQ(strided[0].x(), (0 - 1.5f) / 2.0f * 1.0f);
  EXPECT_FLOAT_EQ(strided[0].z(), 1.0f);
  EXPECT_FLOAT_EQ(strided[1].x(), (2 - 1.5f) / 2.0f * 2.0f);
  EXPECT_FLOAT_EQ(strided[1].y(), (2 - 1.5f) / 2.0f * 2.0f);
  EXPECT_THROW(backproject_depth(depth, cam, 0), Error);
}

TEST(BenchPeers, OptionsAreValidated) {
  PeerOptions o;
  EXPECT_NO_THROW(o.validate());
  o.voxel_m = 0.0f;
  EXPECT_THROW(o.validate(), Error);
  o = PeerOptions();
  o.pixel_stride = 0;
  EXPECT_THROW(o.validate(), Error);
}

TEST(BenchPeers, UnknownPeer) {
  auto source = datasets::open_synthetic("room", {});
  EXPECT_THROW(run_peer(*source, "icp", PeerOptions()), Error);
}

// Five frames of the noisy room at 320x240: frame-to-frame GICP / NDT must follow the camera to within a couple of
// centimetres (each step moves it ~1 cm; the peers' own accuracy on this scene is a few millimetres per pair,
// bench/results/registration.md).
TEST(BenchPeers, TracksTheSyntheticRoom) {
  if (peer_names().empty()) GTEST_SKIP() << "built without PCL: no peers";
  for (const std::string& method : peer_names()) {
    SCOPED_TRACE(method);
    datasets::SyntheticOptions s;
    s.frames = 5;
    s.camera = PinholeCamera::preset("ros").scaled(1);
    auto source = datasets::open_synthetic("room", s);
    const PeerRun run = run_peer(*source, method, PeerOptions(), 0);
    ASSERT_EQ(run.frames.size(), 5u);
    EXPECT_EQ(run.frames_lost(), 0) << run.frames.back().message;
    EXPECT_GT(run.frames[1].ms_track, 0.0);
    const Trajectory est = run.estimate();
    ASSERT_EQ(est.size(), 5u);
    // The first pose is the ground truth's.
    EXPECT_LT((est[0].T_world_camera.translation() - source->ground_truth()[0].T_world_camera.translation()).norm(),
              1e-9);
    const EvalResult e = evaluate_trajectory(source->ground_truth(), est);
    EXPECT_LT(e.ate.error_m.rmse, 0.02);
  }
}

TEST(BenchPeers, MaxFramesAndStop) {
  if (peer_names().empty()) GTEST_SKIP() << "built without PCL: no peers";
  datasets::SyntheticOptions s;
  s.frames = 6;
  s.camera = PinholeCamera::preset("ros").scaled(2);
  auto source = datasets::open_synthetic("room", s);
  EXPECT_EQ(run_peer(*source, "gicp", PeerOptions(), 2).frames.size(), 2u);
  std::atomic<bool> stop{true};
  auto again = datasets::open_synthetic("room", s);
  const PeerRun stopped = run_peer(*again, "gicp", PeerOptions(), 0, &stop);
  EXPECT_TRUE(stopped.interrupted);
  EXPECT_TRUE(stopped.frames.empty());
}

}  // namespace
}  // namespace hf::bench
