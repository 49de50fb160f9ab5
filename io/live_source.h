// Live capture behind the FrameSource interface: a capture device (OpenNI2, V4L2, libcamera, or a recording played
// back at its own rate) feeds a bounded queue from its own thread, and the pipeline takes frames from the queue.
//
//   device thread:  grab() -> paired depth + colour -> queue (when full: the OLDEST queued frame is dropped, counted)
//   caller:         next() -> the oldest queued frame, waiting at most LiveOptions::frame_timeout
//
// So a tracker slower than the sensor never makes the sensor wait: it sees the freshest frames and the report says
// how many it missed (CaptureStats). A finite source (a file) can ask for lossless delivery instead
// (drop_when_full = false): the capture thread then waits for room, as PrefetchingSource does.
//
// Ending: next() returns `end` with an empty message when a finite device has no more frames, and `end` with a
// one-line message naming the device when it failed (unplugged: CaptureStatus::failed) or delivered nothing for
// frame_timeout (first_frame_timeout before the first frame). Nothing here blocks without a time-out: grab() is
// called with grab_slice and must return within it; the destructor stops and joins the thread within one slice.
// Thread-safety: next() from one thread at a time (FrameSource); capture_stats() and the const accessors from any.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "io/frame_source.h"

namespace hf {

// One depth + colour pair as a device delivers it: depth in metres (0 = none) registered to the colour image, both
// of the device camera's size; the time stamp is the device's (seconds, any epoch, increasing).
struct CapturedFrame {
  double timestamp_s = 0.0;
  DepthImage depth;
  ColorImage color;
  std::optional<SE3> T_world_camera_gt;  // a replayed recording's ground truth (io/replay_source.h); else none
  std::chrono::steady_clock::time_point arrival;  // set by LiveSource when the frame is queued
};

enum class CaptureStatus { frame, timeout, end, failed };

struct CaptureResult {
  CaptureStatus status = CaptureStatus::timeout;
  CapturedFrame frame;  // status frame only
  std::string message;  // failed: "openni2://...: what happened" (one line)
};

// The two results a back-end's grab() builds: a frame, and a failure "DEVICE: what".
inline CaptureResult capture_frame(CapturedFrame frame) {
  CaptureResult r;
  r.status = CaptureStatus::frame;
  r.frame = std::move(frame);
  return r;
}
inline CaptureResult capture_failed(const std::string& device_name, const std::string& what) {
  CaptureResult r;
  r.status = CaptureStatus::failed;
  r.message = device_name + ": " + what;
  return r;
}

// A back-end's device, opened and streaming. Implementations: io/openni2_capture.h, io/v4l2_capture.h,
// io/libcamera_capture.h. Called from the LiveSource's capture thread only (accessors: any thread, fixed at
// construction).
class CaptureDevice {
 public:
  virtual ~CaptureDevice() = default;
  // Waits at most `timeout` for the next paired frame; never throws for device trouble (that is `failed`).
  virtual CaptureResult grab(std::chrono::milliseconds timeout) = 0;
  virtual const PinholeCamera& camera() const = 0;
  virtual const std::string& camera_origin() const = 0;
  virtual const std::string& name() const = 0;  // e.g. "OpenNI2 'PrimeSense Carmine 1.09' (openni2://1d27/0601@3/7)"
  // Frames a recording holds; nullopt for a live device (then size() is kUnknownFrameCount).
  virtual std::optional<size_t> frame_count() const { return std::nullopt; }
};

struct LiveOptions {
  // Frames queued between capture and processing. 2: one being handed over, one arriving; more only adds latency.
  size_t queue_frames = 2;
  // true (live): a full queue drops its oldest frame; false (recordings): the capture thread waits for room.
  bool drop_when_full = true;
  // No frame for this long ends the source as "device stopped delivering frames". Sensors run at 15-90 Hz, so
  // 3 s is many frames of silence; the first frame gets longer because devices take a second or two to start.
  std::chrono::milliseconds frame_timeout{3000};
  std::chrono::milliseconds first_frame_timeout{10000};
  // grab()'s time-out, and so how soon the thread notices the destructor (or a silent device).
  std::chrono::milliseconds grab_slice{100};
};

class LiveSource : public FrameSource {
 public:
  // Takes the opened device and starts the capture thread. Throws hf::Error for a null device, queue_frames 0 or
  // non-positive time-outs.
  LiveSource(std::unique_ptr<CaptureDevice> device, const LiveOptions& options = {});
  ~LiveSource() override;
  LiveSource(const LiveSource&) = delete;
  LiveSource& operator=(const LiveSource&) = delete;

  FrameRead next() override;
  const PinholeCamera& camera() const override { return device_->camera(); }
  const std::string& camera_origin() const override { return device_->camera_origin(); }
  size_t size() const override;
  const std::string& name() const override { return device_->name(); }
  const Trajectory& ground_truth() const override { return no_ground_truth_; }
  std::optional<CaptureStats> capture_stats() const override;

 private:
  using Clock = std::chrono::steady_clock;
  void run();
  void finish(const std::string& message);  // called with mutex_ held

  std::unique_ptr<CaptureDevice> device_;
  LiveOptions options_;
  Trajectory no_ground_truth_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<CapturedFrame> queue_;
  bool finished_ = false;        // the thread has ended (device end, failure or silence)
  std::string end_message_;      // why, when not a plain end
  bool stop_ = false;            // destructor
  size_t captured_ = 0, delivered_ = 0, dropped_ = 0, next_index_ = 0;
  std::vector<double> dropped_timestamps_;
  std::optional<Clock::time_point> first_capture_, last_capture_, last_delivery_;
  std::thread thread_;  // last: started after everything it uses exists
};

}  // namespace hf
