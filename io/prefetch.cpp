#include "io/prefetch.h"

#include "core/error.h"

namespace hf {

PrefetchingSource::PrefetchingSource(std::unique_ptr<FrameSource> inner, size_t capacity)
    : inner_(std::move(inner)), capacity_(capacity) {
  if (!inner_) throw Error("PrefetchingSource: no frame source given");
  if (capacity_ == 0) throw Error("PrefetchingSource: capacity must be at least 1");
  thread_ = std::thread([this] { run(); });
}

PrefetchingSource::~PrefetchingSource() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  not_full_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void PrefetchingSource::run() {
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      not_full_.wait(lock, [this] { return stop_ || queue_.size() < capacity_; });
      if (stop_) break;
    }
    // Decode outside the lock: this is the work that overlaps with the consumer.
    FrameRead read;
    std::exception_ptr error;
    try {
      read = inner_->next();
    } catch (...) {
      error = std::current_exception();
    }
    std::lock_guard<std::mutex> lock(mutex_);
    if (error) {
      error_ = error;
      break;
    }
    const bool end = read.status == FrameStatus::end;
    if (!end) queue_.push_back(std::move(read));
    not_empty_.notify_one();
    if (end) break;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
  not_empty_.notify_all();
}

FrameRead PrefetchingSource::next() {
  std::unique_lock<std::mutex> lock(mutex_);
  not_empty_.wait(lock, [this] { return !queue_.empty() || finished_; });
  if (!queue_.empty()) {
    FrameRead read = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    not_full_.notify_one();
    return read;
  }
  if (error_) {
    std::exception_ptr error = error_;
    error_ = nullptr;
    std::rethrow_exception(error);
  }
  return FrameRead{};
}

}  // namespace hf
