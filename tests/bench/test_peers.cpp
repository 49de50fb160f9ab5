// The peer runner: back-projection, and PCL GICP / NDT and (where built) Open3D frame-to-frame odometry on a short
// synthetic room.
#include <gtest/gtest.h>

#include <algorithm>

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

bool built(const std::string& peer) {
  const std::vector<std::string> names = peer_names();
  return std::find(names.begin(), names.end(), peer) != names.end();
}

// Five frames of the noisy room at 320x240: frame-to-frame GICP / NDT must follow the camera to within a couple of
// centimetres (each step moves it ~1 cm; the peers' own accuracy on this scene is a few millimetres per pair,
// bench/results/registration.md).
void expect_tracks_the_room(const std::vector<std::string>& methods) {
  for (const std::string& method : methods) {
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

TEST(BenchPeers, TracksTheSyntheticRoom) {
  if (!built("gicp")) GTEST_SKIP() << "built without PCL: no PCL peers";
  expect_tracks_the_room({"gicp", "ndt"});
}

// Open3D's point-to-plane ICP, coloured ICP and hybrid RGB-D odometry (bench/open3d_reference.h), built only where
// libopen3d-dev is installed: the same room, the same bound.
TEST(BenchPeers, Open3dPeersTrackTheSyntheticRoom) {
  if (!built("o3d-icp")) {
    GTEST_SKIP() << "built without Open3D (optional: apt-get install libopen3d-dev, then reconfigure): no Open3D peers";
  }
  expect_tracks_the_room({"o3d-icp", "o3d-colored-icp", "o3d-rgbd"});
}

// A peer of a library this build lacks is refused by name, not run.
TEST(BenchPeers, PeerOfAMissingLibraryIsRefused) {
  auto source = datasets::open_synthetic("room", {});
  for (const std::string peer : {"gicp", "ndt", "o3d-icp", "o3d-colored-icp", "o3d-rgbd"}) {
    if (built(peer)) continue;
    EXPECT_THROW(run_peer(*source, peer, PeerOptions()), Error) << peer;
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
