// LiveSource: the bounded queue between a capture device and processing (drops and counts, or waits for a
// recording), endings (device end, failure, silence) and their messages, and shutdown without hanging.
#include "io/live_source.h"

#include <gtest/gtest.h>

#include <thread>

#include "core/error.h"
#include "io/frame_pairing.h"
#include "live_test_device.h"

using hf::test::FakeDevice;
using hf::test::FakeEnding;
using namespace std::chrono_literals;

namespace {

hf::LiveOptions fast_options(bool drop) {
  hf::LiveOptions o;
  o.drop_when_full = drop;
  o.queue_frames = 2;
  o.grab_slice = 20ms;
  o.frame_timeout = 300ms;
  o.first_frame_timeout = 300ms;
  return o;
}

}  // namespace

TEST(LiveSource, SlowConsumerSeesTheFreshestFramesAndEveryFrameIsCountedOnce) {
  // The consumer takes nothing until the device has delivered all 40 frames (a tracker far slower than the
  // sensor): the queue of 2 must hold the last two, and the other 38 be dropped and counted, never queued up.
  auto device = std::make_unique<FakeDevice>(40, FakeEnding::end, 1ms);
  auto* raw = device.get();
  hf::LiveSource source(std::move(device), fast_options(true));
  EXPECT_EQ(source.size(), 40u);  // a finite fake announces its length
  while (raw->grabbed.load() < 40) std::this_thread::sleep_for(1ms);
  std::vector<double> stamps;
  for (;;) {
    const hf::FrameRead r = source.next();
    if (r.status == hf::FrameStatus::end) {
      EXPECT_EQ(r.message, "");  // a plain end
      break;
    }
    ASSERT_EQ(r.status, hf::FrameStatus::ok);
    EXPECT_EQ(r.frame.index, stamps.size());  // index counts next() results, not device frames
    stamps.push_back(r.frame.timestamp_s);
  }
  ASSERT_EQ(stamps.size(), 2u);
  EXPECT_DOUBLE_EQ(stamps[0], 38 / 30.0);
  EXPECT_DOUBLE_EQ(stamps[1], 39 / 30.0);
  const hf::CaptureStats s = *source.capture_stats();
  EXPECT_EQ(s.captured, 40u);
  EXPECT_EQ(s.delivered, 2u);
  EXPECT_EQ(s.dropped, 38u);
  EXPECT_GT(s.input_fps, 0.0);
}

TEST(LiveSource, RecordingModeKeepsEveryFrameInOrder) {
  auto device = std::make_unique<FakeDevice>(25, FakeEnding::end);
  hf::LiveSource source(std::move(device), fast_options(false));
  size_t n = 0;
  for (hf::FrameRead r = source.next(); r.status != hf::FrameStatus::end; r = source.next()) {
    const hf::CapturedFrame expected = hf::test::fake_frame(int(n), 16, 12, 1.0 / 30.0, 1);
    EXPECT_DOUBLE_EQ(r.frame.timestamp_s, expected.timestamp_s);
    EXPECT_EQ(r.frame.color.pixels(), expected.color.pixels());
    EXPECT_EQ(r.frame.depth.pixels(), expected.depth.pixels());
    ++n;
    std::this_thread::sleep_for(1ms);
  }
  EXPECT_EQ(n, 25u);
  EXPECT_EQ(source.capture_stats()->dropped, 0u);
}

TEST(LiveSource, UnpluggedDeviceEndsWithItsMessageAfterTheFramesItGave) {
  hf::LiveSource source(std::make_unique<FakeDevice>(3, FakeEnding::fail), fast_options(false));
  int frames = 0;
  hf::FrameRead r;
  while ((r = source.next()).status == hf::FrameStatus::ok) ++frames;
  EXPECT_EQ(frames, 3);
  EXPECT_EQ(r.message, "fake device 'test': the device was disconnected");
  EXPECT_EQ(source.next().status, hf::FrameStatus::end);  // and stays ended
  EXPECT_EQ(source.size(), hf::kUnknownFrameCount);
}

TEST(LiveSource, SilentDeviceEndsAfterTheTimeoutNamingIt) {
  hf::LiveSource source(std::make_unique<FakeDevice>(2, FakeEnding::silent), fast_options(true));
  EXPECT_EQ(source.next().status, hf::FrameStatus::ok);
  EXPECT_EQ(source.next().status, hf::FrameStatus::ok);
  const auto t0 = std::chrono::steady_clock::now();
  const hf::FrameRead r = source.next();
  const auto waited = std::chrono::steady_clock::now() - t0;
  EXPECT_EQ(r.status, hf::FrameStatus::end);
  EXPECT_NE(r.message.find("fake device 'test': no frame for 300 ms"), std::string::npos) << r.message;
  EXPECT_LT(waited, 5s);  // bounded: the frame time-out plus a grab slice, far below this
}

TEST(LiveSource, NeverStartingDeviceEndsWithTheOpeningMessage) {
  hf::LiveSource source(std::make_unique<FakeDevice>(0, FakeEnding::silent), fast_options(true));
  const hf::FrameRead r = source.next();
  EXPECT_EQ(r.status, hf::FrameStatus::end);
  EXPECT_NE(r.message.find("after opening it"), std::string::npos) << r.message;
}

TEST(LiveSource, DestructionWhileCapturingDoesNotHang) {
  auto device = std::make_unique<FakeDevice>(1000000, FakeEnding::end, 1ms);
  auto* raw = device.get();
  {
    hf::LiveSource source(std::move(device), fast_options(true));
    while (raw->grabbed.load() < 5) std::this_thread::sleep_for(1ms);
  }  // joined here
  SUCCEED();
}

TEST(LiveSource, RefusesBadArguments) {
  EXPECT_THROW(hf::LiveSource(nullptr), hf::Error);
  hf::LiveOptions o;
  o.queue_frames = 0;
  EXPECT_THROW(hf::LiveSource(std::make_unique<FakeDevice>(1, FakeEnding::end), o), hf::Error);
}

TEST(StampPairer, PairsAcrossLatencyAndDiscardsOrphans) {
  hf::StampPairer pairer(0.010);
  // Depth arrives three frames ahead of colour (stamps on a common clock, 30 Hz).
  for (int k = 0; k < 3; ++k) pairer.offer_depth(k / 30.0, hf::DepthImage(2, 2, float(k)));
  EXPECT_FALSE(pairer.take());
  for (int k = 0; k < 3; ++k) {
    pairer.offer_color(k / 30.0 + 0.004, hf::ColorImage(2, 2, {std::uint8_t(k), 0, 0}));  // 4 ms later
    const auto f = pairer.take();
    ASSERT_TRUE(f) << k;
    EXPECT_EQ(f->depth(0, 0), float(k));
    EXPECT_EQ(f->color(0, 0).r, k);
    EXPECT_DOUBLE_EQ(f->timestamp_s, k / 30.0 + 0.004);  // the colour stamp
  }
  EXPECT_EQ(pairer.discarded(), 0u);
  // A colour frame without a depth partner within 10 ms is discarded once a later pair forms.
  pairer.offer_color(1.000, hf::ColorImage(2, 2));
  pairer.offer_color(1.100, hf::ColorImage(2, 2));
  pairer.offer_depth(1.105, hf::DepthImage(2, 2));
  ASSERT_TRUE(pairer.take());
  EXPECT_EQ(pairer.discarded(), 1u);
  EXPECT_FALSE(pairer.holds_depth());
}
