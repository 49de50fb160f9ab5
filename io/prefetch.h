// PrefetchingSource: decodes frames of any FrameSource on a background thread, so image decoding overlaps with
// the pipeline's work instead of stalling it.
//
// The wrapper owns the inner source and one thread that calls inner->next() until end (or destruction), keeping
// up to `capacity` results (ok and bad_frame alike, in order) in a bounded queue; next() blocks only while the
// queue is empty. Results come out exactly in the inner source's order. An exception thrown by inner->next() is
// captured and rethrown by the next() that reaches it, after the results produced before it; the thread then
// stops and later calls return end. The destructor stops the thread (waiting for at most the decode in progress)
// and joins it; nothing is leaked or left running.
// Thread-safety: next() from one thread at a time (as FrameSource); the const accessors forward to the inner
// source, whose metadata is immutable (FrameSource contract), so they are safe from any thread.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "io/frame_source.h"

namespace hf {

class PrefetchingSource : public FrameSource {
 public:
  // Throws hf::Error for a null source or capacity 0. Starts the thread immediately.
  PrefetchingSource(std::unique_ptr<FrameSource> inner, size_t capacity = 4);
  ~PrefetchingSource() override;
  PrefetchingSource(const PrefetchingSource&) = delete;
  PrefetchingSource& operator=(const PrefetchingSource&) = delete;

  FrameRead next() override;
  const PinholeCamera& camera() const override { return inner_->camera(); }
  const std::string& camera_origin() const override { return inner_->camera_origin(); }
  size_t size() const override { return inner_->size(); }
  std::optional<FrameRead> read_at(size_t index) const override { return inner_->read_at(index); }
  const std::string& name() const override { return inner_->name(); }
  const Trajectory& ground_truth() const override { return inner_->ground_truth(); }
  std::optional<CaptureStats> capture_stats() const override { return inner_->capture_stats(); }

  const FrameSource& inner() const { return *inner_; }
  size_t capacity() const { return capacity_; }

 private:
  void run();

  std::unique_ptr<FrameSource> inner_;
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_empty_, not_full_;
  std::deque<FrameRead> queue_;
  std::exception_ptr error_;  // set by the thread; rethrown once by next()
  bool finished_ = false;     // the thread produced end (or failed) and exited its loop
  bool stop_ = false;         // the destructor asks the thread to stop
  std::thread thread_;        // last member: started after everything it uses exists
};

}  // namespace hf
