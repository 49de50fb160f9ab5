#include "io/live_source.h"

#include "core/error.h"

namespace hf {

LiveSource::LiveSource(std::unique_ptr<CaptureDevice> device, const LiveOptions& options)
    : device_(std::move(device)), options_(options) {
  if (!device_) throw Error("LiveSource: no capture device given");
  if (options_.queue_frames == 0) throw Error("LiveSource: queue_frames must be at least 1");
  if (options_.frame_timeout.count() <= 0 || options_.first_frame_timeout.count() <= 0 ||
      options_.grab_slice.count() <= 0)
    throw Error("LiveSource: time-outs must be positive");
  thread_ = std::thread([this] { run(); });
}

LiveSource::~LiveSource() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  not_full_.notify_all();
  if (thread_.joinable()) thread_.join();
}

size_t LiveSource::size() const {
  const std::optional<size_t> n = device_->frame_count();
  return n ? *n : kUnknownFrameCount;
}

void LiveSource::finish(const std::string& message) {
  finished_ = true;
  end_message_ = message;
  not_empty_.notify_all();
}

void LiveSource::run() {
  // Silence is the time spent inside grab() without a frame, so waiting for room in the queue never counts.
  Clock::duration silent{0};
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      if (!options_.drop_when_full)
        not_full_.wait(lock, [this] { return stop_ || queue_.size() < options_.queue_frames; });
      if (stop_) break;
    }
    const Clock::time_point grab_start = Clock::now();
    CaptureResult r;
    try {
      r = device_->grab(options_.grab_slice);
    } catch (const std::exception& e) {
      r.status = CaptureStatus::failed;
      r.message = device_->name() + ": " + e.what();
    }
    const Clock::time_point now = Clock::now();
    std::lock_guard<std::mutex> lock(mutex_);
    if (r.status == CaptureStatus::end) {
      finish("");
      return;
    }
    if (r.status == CaptureStatus::failed) {
      finish(r.message);
      return;
    }
    if (r.status == CaptureStatus::timeout) {
      const auto limit = first_capture_ ? options_.frame_timeout : options_.first_frame_timeout;
      silent += now - grab_start;
      if (silent >= limit) {
        const long ms = long(std::chrono::duration_cast<std::chrono::milliseconds>(limit).count());
        finish(device_->name() + ": no frame for " + std::to_string(ms) + " ms" +
               (first_capture_ ? " (the device stopped delivering: unplugged?)" : " after opening it"));
        return;
      }
      continue;
    }
    silent = Clock::duration{0};
    ++captured_;
    if (!first_capture_) first_capture_ = now;
    last_capture_ = now;
    if (queue_.size() >= options_.queue_frames) {  // only with drop_when_full: the consumer is behind
      dropped_timestamps_.push_back(queue_.front().timestamp_s);
      queue_.pop_front();
      ++dropped_;
    }
    r.frame.arrival = now;
    queue_.push_back(std::move(r.frame));
    not_empty_.notify_one();
  }
  std::lock_guard<std::mutex> lock(mutex_);
  finish("");
}

FrameRead LiveSource::next() {
  std::unique_lock<std::mutex> lock(mutex_);
  // The thread itself ends the source after frame_timeout of silence; the extra slice covers its last grab().
  const auto wait = std::max(options_.frame_timeout, options_.first_frame_timeout) + 2 * options_.grab_slice;
  if (!not_empty_.wait_for(lock, wait, [this] { return !queue_.empty() || finished_; })) {
    FrameRead r;
    r.message = device_->name() + ": no frame within the time-out";
    return r;
  }
  FrameRead r;
  if (queue_.empty()) {
    r.message = end_message_;
    return r;
  }
  CapturedFrame f = std::move(queue_.front());
  queue_.pop_front();
  ++delivered_;
  last_delivery_ = Clock::now();
  r.status = FrameStatus::ok;
  r.frame.index = next_index_++;
  r.frame.timestamp_s = f.timestamp_s;
  r.frame.depth = std::move(f.depth);
  r.frame.color = std::move(f.color);
  r.frame.T_world_camera_gt = f.T_world_camera_gt;
  r.frame.arrival = f.arrival;
  r.frame.depth_file = r.frame.color_file = device_->name();
  lock.unlock();
  not_full_.notify_one();
  return r;
}

std::optional<CaptureStats> LiveSource::capture_stats() const {
  std::lock_guard<std::mutex> lock(mutex_);
  CaptureStats s;
  s.captured = captured_;
  s.delivered = delivered_;
  s.dropped = dropped_;
  s.dropped_timestamps_s = dropped_timestamps_;
  if (first_capture_ && last_capture_ && captured_ > 1) {
    const double span = std::chrono::duration<double>(*last_capture_ - *first_capture_).count();
    // n frames span n - 1 intervals.
    if (span > 0) s.input_fps = double(captured_ - 1) / span;
  }
  if (first_capture_ && last_delivery_ && delivered_ > 1) {
    const double span = std::chrono::duration<double>(*last_delivery_ - *first_capture_).count();
    if (span > 0) s.delivered_fps = double(delivered_ - 1) / span;
  }
  return s;
}

}  // namespace hf
