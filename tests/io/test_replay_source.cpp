// Replay at the recorded rate (io/replay_source.h): frames come at their time stamps, through a camera's
// drop-oldest queue of two, with their ground truth, arrival time and the dropped frames' time stamps. Only lower
// bounds on time are asserted (a loaded machine is late, never early).
#include "io/replay_source.h"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "core/error.h"

namespace {

using namespace std::chrono_literals;

// N tiny frames at 30 Hz, frame i at x = i cm, one of them unreadable.
class Recording : public hf::FrameSource {
 public:
  explicit Recording(size_t n, size_t bad = size_t(-1))
      : n_(n), bad_(bad), camera_(hf::PinholeCamera::preset("ros").scaled(4)) {
    for (size_t i = 0; i < n; ++i) gt_.push_back({double(i) / 30.0, pose(i)});
  }
  static hf::SE3 pose(size_t i) {
    return hf::SE3(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0.01 * double(i), 0, 0));
  }
  hf::FrameRead next() override {
    hf::FrameRead r;
    if (i_ >= n_) return r;
    r.status = i_ == bad_ ? hf::FrameStatus::bad_frame : hf::FrameStatus::ok;
    r.frame.index = i_;
    r.frame.timestamp_s = double(i_) / 30.0;
    if (r.status == hf::FrameStatus::ok) {
      r.frame.depth = hf::DepthImage(camera_.width, camera_.height, 1.0f);
      r.frame.color = hf::ColorImage(camera_.width, camera_.height);
      r.frame.T_world_camera_gt = pose(i_);
    }
    ++i_;
    return r;
  }
  const hf::PinholeCamera& camera() const override { return camera_; }
  const std::string& camera_origin() const override { return name_; }
  size_t size() const override { return n_; }
  const std::string& name() const override { return name_; }
  const hf::Trajectory& ground_truth() const override { return gt_; }

 private:
  size_t n_, bad_, i_ = 0;
  hf::PinholeCamera camera_;
  std::string name_ = "recording";
  hf::Trajectory gt_;
};

TEST(RealtimeReplay, FramesArriveAtTheirTimeStampsWithGroundTruth) {
  constexpr size_t kFrames = 10;
  auto source = hf::open_realtime_replay(std::make_unique<Recording>(kFrames, 4));
  EXPECT_EQ(source->ground_truth().size(), kFrames);
  const auto t0 = std::chrono::steady_clock::now();
  size_t delivered = 0;
  double last_stamp = -1.0;
  for (;;) {
    const hf::FrameRead r = source->next();
    if (r.status == hf::FrameStatus::end) break;
    ASSERT_EQ(r.status, hf::FrameStatus::ok);
    EXPECT_GT(r.frame.timestamp_s, last_stamp);
    EXPECT_NE(r.frame.timestamp_s, 4 / 30.0) << "the unreadable frame is skipped";
    last_stamp = r.frame.timestamp_s;
    ASSERT_TRUE(r.frame.T_world_camera_gt);
    EXPECT_NEAR(r.frame.T_world_camera_gt->translation().x(), r.frame.timestamp_s * 0.3, 1e-9);
    ASSERT_TRUE(r.frame.arrival);
    ++delivered;
  }
  // The last frame is due 9/30 s after the first: the replay is never faster than the recording.
  EXPECT_GE(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), 0.9 * 9.0 / 30.0);
  const hf::CaptureStats s = *source->capture_stats();
  EXPECT_EQ(s.captured, kFrames - 1);
  EXPECT_EQ(s.delivered + s.dropped, s.captured);
  EXPECT_EQ(s.delivered, delivered);
  EXPECT_EQ(s.dropped_timestamps_s.size(), s.dropped);
}

TEST(RealtimeReplay, SlowConsumerGetsTheFreshestTwoAndTheDroppedStamps) {
  constexpr size_t kFrames = 12;
  hf::ReplayOptions o;
  o.speed = 10.0;
  auto source = hf::open_realtime_replay(std::make_unique<Recording>(kFrames), o);
  // Take nothing until the whole recording was fed (11/300 s at speed 10, with a wide margin).
  while (source->capture_stats()->captured < kFrames) std::this_thread::sleep_for(5ms);
  std::vector<double> stamps;
  for (hf::FrameRead r = source->next(); r.status == hf::FrameStatus::ok; r = source->next())
    stamps.push_back(r.frame.timestamp_s);
  ASSERT_EQ(stamps.size(), 2u);
  EXPECT_DOUBLE_EQ(stamps[1], 11 / 30.0);
  const hf::CaptureStats s = *source->capture_stats();
  EXPECT_EQ(s.dropped, kFrames - 2);
  ASSERT_EQ(s.dropped_timestamps_s.size(), kFrames - 2);
  for (size_t i = 0; i < s.dropped_timestamps_s.size(); ++i)
    EXPECT_DOUBLE_EQ(s.dropped_timestamps_s[i], double(i) / 30.0);
}

TEST(RealtimeReplay, BadArguments) {
  EXPECT_THROW(hf::open_realtime_replay(nullptr), hf::Error);
  hf::ReplayOptions o;
  o.speed = 0.0;
  EXPECT_THROW(hf::open_realtime_replay(std::make_unique<Recording>(2), o), hf::Error);
}

}  // namespace
