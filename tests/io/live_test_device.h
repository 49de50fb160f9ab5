// A scripted CaptureDevice for the live-capture tests: deterministic synthetic frames (by seed), a chosen frame
// period, and a chosen ending (a finite recording, a failure, or silence), with no device anywhere.
#pragma once

#include <atomic>
#include <chrono>
#include <random>
#include <thread>

#include "io/live_source.h"

namespace hf::test {

enum class FakeEnding { end, fail, silent };

// Frame k: stamp k * period_s, depth 0.5 + k mm quantised to whole millimetres (as a sensor reports), colour a
// seeded pattern; so every value can be checked exactly after a round trip.
inline CapturedFrame fake_frame(int k, int width, int height, double period_s, unsigned seed) {
  CapturedFrame f;
  f.timestamp_s = k * period_s;
  f.depth = DepthImage(width, height);
  f.color = ColorImage(width, height);
  std::mt19937 rng(seed * 7919u + unsigned(k));
  std::uniform_int_distribution<int> mm(300, 4000), byte(0, 255);
  for (int y = 0; y < height; ++y)
    for (int x = 0; x < width; ++x) {
      f.depth(x, y) = (x + y + k) % 11 == 0 ? 0.0f : float(mm(rng) / 1000.0);
      f.color(x, y) = {std::uint8_t(byte(rng)), std::uint8_t(byte(rng)), std::uint8_t(byte(rng))};
    }
  return f;
}

class FakeDevice : public CaptureDevice {
 public:
  FakeDevice(int frames, FakeEnding ending, std::chrono::milliseconds period = std::chrono::milliseconds(0),
             int width = 16, int height = 12, unsigned seed = 1)
      : frames_(frames), ending_(ending), period_(period), width_(width), height_(height), seed_(seed) {
    camera_.width = width;
    camera_.height = height;
    camera_.fx = camera_.fy = 20.0;
    camera_.cx = (width - 1) / 2.0;
    camera_.cy = (height - 1) / 2.0;
  }
  CaptureResult grab(std::chrono::milliseconds timeout) override {
    CaptureResult r;
    if (next_ >= frames_) {
      if (ending_ == FakeEnding::end) r.status = CaptureStatus::end;
      if (ending_ == FakeEnding::fail) {
        r.status = CaptureStatus::failed;
        r.message = name_ + ": the device was disconnected";
      }
      if (ending_ == FakeEnding::silent) std::this_thread::sleep_for(timeout);
      return r;
    }
    if (period_.count() > 0) std::this_thread::sleep_for(std::min(period_, timeout));
    r.status = CaptureStatus::frame;
    r.frame = fake_frame(next_++, width_, height_, 1.0 / 30.0, seed_);
    grabbed.store(next_);
    return r;
  }
  const PinholeCamera& camera() const override { return camera_; }
  const std::string& camera_origin() const override { return origin_; }
  const std::string& name() const override { return name_; }
  std::optional<size_t> frame_count() const override {
    return ending_ == FakeEnding::end ? std::optional<size_t>(size_t(frames_)) : std::nullopt;
  }
  std::atomic<int> grabbed{0};

 private:
  int frames_;
  FakeEnding ending_;
  std::chrono::milliseconds period_;
  int width_, height_;
  unsigned seed_;
  int next_ = 0;
  PinholeCamera camera_;
  std::string origin_ = "fake intrinsics", name_ = "fake device 'test'";
};

}  // namespace hf::test
