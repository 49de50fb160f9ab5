// Recording a live source as a TUM folder (io/tum_recorder.h) that the TUM reader replays exactly: same frames,
// same stamps, same camera; limits, an existing folder, and an empty recording.
#include "io/tum_recorder.h"

#include <gtest/gtest.h>

#include "core/error.h"
#include "io/dataset.h"
#include "io/tum_dataset.h"
#include "live_test_device.h"
#include "test_dataset_util.h"

using hf::test::FakeDevice;
using hf::test::FakeEnding;

namespace {
hf::LiveOptions lossless() {
  hf::LiveOptions o;
  o.drop_when_full = false;
  o.grab_slice = std::chrono::milliseconds(20);
  o.frame_timeout = o.first_frame_timeout = std::chrono::milliseconds(300);
  return o;
}
}  // namespace

TEST(TumRecorder, ReplaysExactlyWhatTheDeviceGave) {
  hf::test::TempDir tmp("tum_recorder");
  const std::string dir = tmp / "rec";
  hf::LiveSource source(std::make_unique<FakeDevice>(12, FakeEnding::fail, std::chrono::milliseconds(0), 24, 18, 9),
                        lossless());
  const hf::RecordResult r = hf::record_tum_folder(source, dir);
  EXPECT_EQ(r.frames, 12);
  EXPECT_EQ(r.input_ended, "fake device 'test': the device was disconnected");  // ended by the device, still written
  hf::TumDataset replay(dir);
  ASSERT_EQ(replay.size(), 12u);
  EXPECT_EQ(replay.camera().describe(), source.camera().describe());
  EXPECT_NE(replay.camera_origin().find("camera.json"), std::string::npos);
  for (int k = 0; k < 12; ++k) {
    const hf::FrameRead f = replay.next();
    ASSERT_EQ(f.status, hf::FrameStatus::ok) << f.message;
    const hf::CapturedFrame want = hf::test::fake_frame(k, 24, 18, 1.0 / 30.0, 9);
    EXPECT_NEAR(f.frame.timestamp_s, want.timestamp_s, 5e-7);  // printed with 6 decimals
    EXPECT_EQ(f.frame.color.pixels(), want.color.pixels());
    // Whole millimetres are 5 units at 5000 per metre: exact up to float rounding of the division.
    for (size_t i = 0; i < want.depth.size(); ++i)
      ASSERT_NEAR(f.frame.depth.pixels()[i], want.depth.pixels()[i], 1e-7) << "frame " << k << " pixel " << i;
  }
  EXPECT_EQ(replay.next().status, hf::FrameStatus::end);
}

TEST(TumRecorder, StopsAtTheFrameLimitAndRefusesAnExistingFolder) {
  hf::test::TempDir tmp("tum_recorder_limit");
  const std::string dir = tmp / "rec";
  {
    hf::LiveSource source(std::make_unique<FakeDevice>(100, FakeEnding::end), lossless());
    hf::RecordLimits limits;
    limits.frames = 5;
    EXPECT_EQ(hf::record_tum_folder(source, dir, limits).frames, 5);
    EXPECT_EQ(hf::TumDataset(dir).size(), 5u);
  }
  hf::LiveSource again(std::make_unique<FakeDevice>(3, FakeEnding::end), lossless());
  try {
    hf::record_tum_folder(again, dir);
    FAIL() << "an existing folder was replaced";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("already exists"), std::string::npos) << e.what();
  }
  EXPECT_EQ(hf::TumDataset(dir).size(), 5u);  // untouched
}

TEST(TumRecorder, StopFlagEndsTheRecordingWithTheFramesSoFar) {
  hf::test::TempDir tmp("tum_recorder_stop");
  hf::LiveSource source(std::make_unique<FakeDevice>(1000, FakeEnding::end), lossless());
  std::atomic<bool> stop{false};
  hf::RecordLimits limits;
  limits.stop = &stop;
  limits.progress = [&](long n) {
    if (n == 4) stop = true;
  };
  const hf::RecordResult r = hf::record_tum_folder(source, tmp / "rec", limits);
  EXPECT_TRUE(r.interrupted);
  EXPECT_EQ(r.frames, 4);
  EXPECT_EQ(hf::TumDataset(tmp / "rec").size(), 4u);
}

TEST(TumRecorder, NoFrameMeansNoFolderAndAnError) {
  hf::test::TempDir tmp("tum_recorder_empty");
  hf::LiveSource source(std::make_unique<FakeDevice>(0, FakeEnding::fail), lossless());
  try {
    hf::record_tum_folder(source, tmp / "rec");
    FAIL() << "an empty recording was written";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("no frame recorded (fake device 'test': the device was disconnected)"),
              std::string::npos)
        << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(tmp / "rec"));
  for (const auto& e : std::filesystem::directory_iterator(tmp.path)) ADD_FAILURE() << "left behind: " << e.path();
}
