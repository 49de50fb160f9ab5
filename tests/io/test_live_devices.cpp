// The device back-ends without hardware: OpenNI2 through its own Dummy driver (a real driver that streams
// 320x240 depth and colour at 30 Hz) and its recorder and file driver (.oni round trip); the open paths of every
// back-end for their one-line errors; real devices only where present (skipped with a message otherwise).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <map>
#include <thread>
#include <unistd.h>

#include "core/error.h"
#include "io/live_input.h"
#include "io/v4l2_capture.h"
#include "test_dataset_util.h"
#if HF_HAVE_OPENNI2
#include <OpenNI.h>
#endif

namespace {

std::string open_error(const std::string& input, hf::LiveInputOptions o = {}) {
  try {
    hf::open_live_input(input, o);
  } catch (const hf::Error& e) {
    return e.what();
  }
  return "opened";
}

hf::LiveInputOptions dummy_options() {
  hf::LiveInputOptions o = hf::live_input_options("320x240@30", "");
  o.live.frame_timeout = std::chrono::milliseconds(2000);
  o.live.first_frame_timeout = std::chrono::milliseconds(3000);
  return o;
}

}  // namespace

TEST(LiveInput, UnknownFormsAndModesAreOneLineErrors) {
  EXPECT_TRUE(hf::is_live_input("openni2://"));
  EXPECT_TRUE(hf::is_live_input("a/b/take.oni"));
  EXPECT_FALSE(hf::is_live_input("data/rgbd_dataset_freiburg1_desk"));
  EXPECT_NE(open_error("rtsp://camera").find("not a live input; live inputs are openni2://"), std::string::npos);
  EXPECT_THROW(hf::live_input_options("640x480@", ""), hf::Error);
  EXPECT_THROW(hf::live_input_options("0x480@30", ""), hf::Error);
  const hf::LiveInputOptions o = hf::live_input_options("1280x720", "");
  EXPECT_EQ(o.width, 1280);
  EXPECT_EQ(o.fps, 30);
}

TEST(LiveInput, CameraChoiceScalesPresetsToTheStream) {
  const hf::CameraChoice c = hf::choose_live_camera("", std::nullopt, "", 320, 240);
  EXPECT_DOUBLE_EQ(c.camera.fx, 262.5);
  EXPECT_DOUBLE_EQ(c.camera.cx, 159.5);  // (319.5 + 0.5) / 2 - 0.5
  EXPECT_NE(c.origin.find("scaled from 640x480"), std::string::npos) << c.origin;
  hf::PinholeCamera device;
  device.fx = 570.3;
  const hf::CameraChoice d = hf::choose_live_camera("", device, "the device's fields of view", 640, 480);
  EXPECT_DOUBLE_EQ(d.camera.fx, 570.3);
  EXPECT_EQ(hf::choose_live_camera("fr1", device, "x", 640, 480).camera.fx, hf::PinholeCamera::preset("fr1").fx);
}

TEST(V4l2Capture, OpenErrorsNameTheNode) {
  EXPECT_NE(open_error("v4l2:///dev/video-none").find("v4l2:///dev/video-none: no such node; present: "),
            std::string::npos);
  EXPECT_NE(open_error("v4l2:///dev/null").find("v4l2:///dev/null: not a V4L2 device"), std::string::npos)
      << open_error("v4l2:///dev/null");
  EXPECT_NE(open_error("v4l2://dev/video0").find("expected absolute node paths"), std::string::npos);
  EXPECT_EQ(hf::parse_v4l2_nodes("/dev/video0+/dev/video2"), (std::vector<std::string>{"/dev/video0", "/dev/video2"}));
}

TEST(V4l2Capture, RealNodeStreams) {
  if (!std::filesystem::exists("/dev/video0")) GTEST_SKIP() << "no /dev/video0 on this machine: no V4L2 device to test";
  auto source = hf::open_live_input("v4l2:///dev/video0");
  const hf::FrameRead r = source->next();
  EXPECT_EQ(r.status, hf::FrameStatus::ok) << r.message;
}

TEST(LibcameraCapture, AbsentCameraIsNamed) {
#if HF_HAVE_LIBCAMERA
  EXPECT_NE(open_error("libcamera://no-such-camera")
                .find("libcamera://no-such-camera: no such camera; libcamera sees: "),
            std::string::npos);
#else
  EXPECT_NE(open_error("libcamera://x").find("not built in"), std::string::npos);
#endif
}

TEST(Devices, EveryBackendAnswers) {
  const std::vector<hf::DeviceListing> all = hf::list_devices();
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[0].backend, "openni2");
  EXPECT_EQ(all[1].backend, "v4l2");
  EXPECT_EQ(all[2].backend, "libcamera");
  for (const auto& l : all) EXPECT_TRUE(!l.devices.empty() || !l.note.empty()) << l.backend << " said nothing";
}

#if HF_HAVE_OPENNI2

TEST(OpenNi2Capture, DummyDriverStreamsPairedFramesThroughTheQueue) {
  auto source = hf::open_live_input("openni2://Dummy", dummy_options());
  EXPECT_NE(source->name().find("openni2://Dummy"), std::string::npos) << source->name();
  EXPECT_EQ(source->size(), hf::kUnknownFrameCount);
  EXPECT_EQ(source->camera().width, 320);
  // The Dummy reports no field of view and cannot register depth: the preset, and the report says both.
  EXPECT_NE(source->camera_origin().find("preset ros"), std::string::npos) << source->camera_origin();
  EXPECT_NE(source->camera_origin().find("NOT registered"), std::string::npos) << source->camera_origin();
  double last = -1.0;
  for (int i = 0; i < 8; ++i) {
    const hf::FrameRead r = source->next();
    ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
    ASSERT_EQ(r.frame.depth.width(), 320);
    ASSERT_EQ(r.frame.color.height(), 240);
    // The driver stamps frame n at n * 33000 us on both streams, so a pair has one stamp of that grid.
    const double n = r.frame.timestamp_s / 0.033;
    EXPECT_NEAR(n, std::round(n), 1e-6) << r.frame.timestamp_s;
    EXPECT_GT(r.frame.timestamp_s, last);
    last = r.frame.timestamp_s;
    EXPECT_EQ(r.frame.depth(5, 0), 2.0f);         // the driver writes 2000 mm into row 0
    EXPECT_EQ(r.frame.color(0, 0).b, 255);        // and a blue first pixel
  }
  const hf::CaptureStats s = *source->capture_stats();
  EXPECT_GE(s.captured, 8u);
  EXPECT_GE(s.captured, s.delivered + s.dropped);  // the rest is still queued
}

TEST(OpenNi2Capture, OpenErrorsSayWhatWasAskedAndWhatExists) {
  EXPECT_NE(open_error("openni2://no-such-device").find("openni2://no-such-device: cannot open"), std::string::npos);
  EXPECT_NE(open_error("openni2://no-such-device").find("OpenNI2 sees: "), std::string::npos);
  EXPECT_EQ(open_error("/no/such/take.oni"), "/no/such/take.oni: no such recording (.oni file)");
  // Issue 35: a folder or a device with the .oni name says what it is instead of "no such recording".
  const std::filesystem::path folder = std::filesystem::temp_directory_path() / ("hf_take_" + std::to_string(::getpid()) + ".oni");
  std::filesystem::create_directories(folder);
  EXPECT_EQ(open_error(folder.string()),
            folder.string() + ": cannot read recording (.oni file): it is a folder, not a regular file");
  std::filesystem::remove(folder);
  const std::string mode = open_error("openni2://Dummy", hf::live_input_options("640x480@30", ""));
  EXPECT_NE(mode.find("openni2://Dummy: no depth mode at 640x480; the device has 320x240@30 depth 1 mm"),
            std::string::npos)
      << mode;
}

TEST(OpenNi2Capture, RealDeviceStreams) {
  // OpenNI2 lists the Dummy driver's device once a test opened it; only other devices are real.
  std::string uri;
  const hf::DeviceListing openni2 = hf::list_devices().front();
  for (const std::string& d : openni2.devices) {
    const std::string u = d.substr(0, d.find("  "));
    if (u != "openni2://Dummy" && u != "openni2://Oz" && u != "openni2://PingPong") {
      uri = u;
      break;
    }
  }
  if (uri.empty()) GTEST_SKIP() << "no OpenNI2 device connected (OpenNI2's own Dummy driver does not count)";
  auto source = hf::open_live_input(uri);
  EXPECT_EQ(source->next().status, hf::FrameStatus::ok);
}

// OpenNI2's recorder fed by the Dummy driver writes a .oni; our source plays it through OpenNI2's file driver.
TEST(OpenNi2Capture, OniRecordingRoundTripsThroughTheFileDriver) {
  namespace ni = openni;
  hf::test::TempDir tmp("oni");
  const std::string file = tmp / "dummy.oni";
  std::map<std::uint64_t, float> live_depth_row0;  // stamp (us) -> depth of pixel (5, 0) in metres
  ASSERT_EQ(ni::OpenNI::initialize(), ni::STATUS_OK);
  {
    ni::Device device;
    ASSERT_EQ(device.open("Dummy"), ni::STATUS_OK);
    ni::VideoStream depth, color;
    ASSERT_EQ(depth.create(device, ni::SENSOR_DEPTH), ni::STATUS_OK);
    ASSERT_EQ(color.create(device, ni::SENSOR_COLOR), ni::STATUS_OK);
    ni::Recorder recorder;
    ASSERT_EQ(recorder.create(file.c_str()), ni::STATUS_OK);
    ASSERT_EQ(recorder.attach(depth, false), ni::STATUS_OK);
    ASSERT_EQ(recorder.attach(color, false), ni::STATUS_OK);
    ASSERT_EQ(depth.start(), ni::STATUS_OK);
    ASSERT_EQ(color.start(), ni::STATUS_OK);
    ASSERT_EQ(recorder.start(), ni::STATUS_OK);
    ni::VideoFrameRef f;
    while (live_depth_row0.size() < 10) {
      ni::VideoStream* s = &depth;
      int ready = -1;
      ASSERT_EQ(ni::OpenNI::waitForAnyStream(&s, 1, &ready, 2000), ni::STATUS_OK);
      ASSERT_EQ(depth.readFrame(&f), ni::STATUS_OK);
      live_depth_row0[f.getTimestamp()] = static_cast<const std::uint16_t*>(f.getData())[5] * 0.001f;
    }
    // Streams first, then the recorder: the Dummy's frame thread holds a stream's lock while it hands the frame to
    // the attached recorder, which takes the recorder's; stopping the recorder first takes them the other way round
    // and deadlocked libOpenNI2 (seen once in a CI-sized run, 2026-12-07: both threads waiting on each other).
    depth.stop();
    color.stop();
    std::this_thread::sleep_for(std::chrono::milliseconds(70));  // the Dummy's threads poll their stop flag
    recorder.stop();
    recorder.destroy();
    depth.destroy();
    color.destroy();
    device.close();
  }
  ni::OpenNI::shutdown();
  ASSERT_GT(std::filesystem::file_size(file), 320u * 240u * 2u * 5u);  // at least a few raw frames

  hf::LiveInputOptions o = dummy_options();
  auto source = hf::open_live_input(file, o);
  EXPECT_NE(source->name().find("OpenNI2 recording"), std::string::npos) << source->name();
  ASSERT_NE(source->size(), hf::kUnknownFrameCount);  // the file driver knows its length
  EXPECT_GE(source->size(), 8u);
  EXPECT_LE(source->size(), live_depth_row0.size() + 4);
  EXPECT_EQ(source->camera().width, 320);
  size_t played = 0;
  hf::FrameRead r;
  while ((r = source->next()).status == hf::FrameStatus::ok) {
    ++played;
    const auto stamp_us = std::uint64_t(std::llround(r.frame.timestamp_s * 1e6));
    EXPECT_EQ(r.frame.depth(5, 0), 2.0f);
    if (live_depth_row0.count(stamp_us)) {
      EXPECT_EQ(r.frame.depth(5, 0), live_depth_row0[stamp_us]);
    }
  }
  if (played == 0) {
    // OpenNI2 2.2.0.33 as packaged by Debian 12 opens the file (streams, modes and frame counts are right) but its
    // player thread delivers no frame, at any speed, even for a colour-only uncompressed recording. Our source
    // must still end within its time-out with a line naming the recording, never hang.
    EXPECT_NE(r.message.find("OpenNI2 recording"), std::string::npos) << r.message;
    GTEST_SKIP() << "OpenNI2's file driver delivered no frame from the recording its own recorder wrote (known "
                    "defect of this OpenNI2 build); opening, modes, length and the clean time-out were checked";
  }
  EXPECT_GE(played, 1u);
}

#endif
