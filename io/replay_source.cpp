#include "io/replay_source.h"

#include <chrono>
#include <cmath>
#include <optional>
#include <thread>
#include <utility>

#include "core/error.h"

namespace hf {
namespace replay_detail {

using Clock = std::chrono::steady_clock;

// The recording as a capture device: grab() hands out the next frame once the clock reaches its time stamp.
class ReplayDevice : public CaptureDevice {
 public:
  ReplayDevice(std::unique_ptr<FrameSource> recording, double speed)
      : recording_(std::move(recording)), speed_(speed), name_("replay of " + recording_->name()) {}

  CaptureResult grab(std::chrono::milliseconds timeout) override {
    const Clock::time_point deadline = Clock::now() + timeout;
    if (!held_) {
      FrameRead r = recording_->next();
      while (r.status == FrameStatus::bad_frame) r = recording_->next();
      if (r.status == FrameStatus::end) {
        CaptureResult end;
        end.status = CaptureStatus::end;
        return end;
      }
      held_ = std::move(r.frame);
      if (!start_) {
        start_ = Clock::now();
        first_stamp_s_ = held_->timestamp_s;
      }
    }
    // Time stamps out of order (or equal) are due at once: the replay never waits backwards.
    const double offset_s = std::max(0.0, (held_->timestamp_s - first_stamp_s_) / speed_);
    const Clock::time_point due =
        *start_ + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset_s));
    if (due > deadline) {
      std::this_thread::sleep_until(deadline);
      return {};  // timeout: the frame is not due yet
    }
    std::this_thread::sleep_until(due);
    CapturedFrame f;
    f.timestamp_s = held_->timestamp_s;
    f.depth = std::move(held_->depth);
    f.color = std::move(held_->color);
    f.T_world_camera_gt = held_->T_world_camera_gt;
    held_.reset();
    return capture_frame(std::move(f));
  }
  const PinholeCamera& camera() const override { return recording_->camera(); }
  const std::string& camera_origin() const override { return recording_->camera_origin(); }
  const std::string& name() const override { return name_; }
  std::optional<size_t> frame_count() const override {
    const size_t n = recording_->size();
    return n == kUnknownFrameCount ? std::nullopt : std::optional<size_t>(n);
  }
  const Trajectory& ground_truth() const { return recording_->ground_truth(); }

 private:
  std::unique_ptr<FrameSource> recording_;
  double speed_;
  std::string name_;
  std::optional<RgbdFrame> held_;  // read, not yet due
  std::optional<Clock::time_point> start_;
  double first_stamp_s_ = 0.0;
};

// LiveSource with the recording's ground truth (the device's metadata is fixed at construction).
class ReplaySource : public LiveSource {
 public:
  // `device` is the object `owned` points to: LiveSource owns it, this keeps it for ground_truth(), which only
  // reads the recording's immutable trajectory (safe beside the capture thread).
  ReplaySource(std::unique_ptr<ReplayDevice> owned, const ReplayDevice* device, const LiveOptions& options)
      : LiveSource(std::move(owned), options), device_(device) {}
  const Trajectory& ground_truth() const override { return device_->ground_truth(); }

 private:
  const ReplayDevice* device_;
};

}  // namespace replay_detail

std::unique_ptr<FrameSource> open_realtime_replay(std::unique_ptr<FrameSource> recording,
                                                  const ReplayOptions& options) {
  if (!recording) throw Error("realtime replay: no recording given");
  if (!(options.speed > 0) || !std::isfinite(options.speed)) throw Error("realtime replay: speed must be positive");
  LiveOptions live = options.live;
  live.drop_when_full = true;  // a camera's queue: the point of the replay
  auto device = std::make_unique<replay_detail::ReplayDevice>(std::move(recording), options.speed);
  const replay_detail::ReplayDevice* raw = device.get();
  return std::make_unique<replay_detail::ReplaySource>(std::move(device), raw, live);
}

}  // namespace hf
