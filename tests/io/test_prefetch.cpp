// PrefetchingSource: order, bounded look-ahead, exceptions, shutdown.
#include "io/prefetch.h"

#include <gtest/gtest.h>

#include <atomic>
#include <stdexcept>
#include <thread>

#include "core/error.h"

namespace {

// Yields `count` frames whose index and stamp encode their position; frame `bad` is a bad_frame; throws at
// frame `throw_at`. Records how far it ran ahead of what the consumer has taken.
class CountingSource : public hf::FrameSource {
 public:
  CountingSource(size_t count, std::atomic<size_t>* consumed, size_t bad = size_t(-1), size_t throw_at = size_t(-1))
      : count_(count), bad_(bad), throw_at_(throw_at), consumed_(consumed) {}

  hf::FrameRead next() override {
    const size_t i = calls_++;
    if (consumed_) max_ahead_ = std::max(max_ahead_.load(), calls_.load() - consumed_->load());
    if (i == throw_at_) throw std::runtime_error("decoder exploded at " + std::to_string(i));
    hf::FrameRead r;
    if (i >= count_) return r;
    r.status = i == bad_ ? hf::FrameStatus::bad_frame : hf::FrameStatus::ok;
    r.frame.index = i;
    r.frame.timestamp_s = 0.5 * double(i);
    if (i == bad_) r.message = "frame " + std::to_string(i) + ": broken";
    return r;
  }
  const hf::PinholeCamera& camera() const override { return camera_; }
  const std::string& camera_origin() const override { return origin_; }
  size_t size() const override { return count_; }
  const std::string& name() const override { return name_; }
  const hf::Trajectory& ground_truth() const override { return gt_; }

  std::atomic<size_t> calls_{0}, max_ahead_{0};

 private:
  size_t count_, bad_, throw_at_;
  std::atomic<size_t>* consumed_;
  hf::PinholeCamera camera_;
  std::string origin_ = "test", name_ = "counting";
  hf::Trajectory gt_;
};

}  // namespace

TEST(Prefetch, KeepsOrderAndStatusesAndForwardsMetadata) {
  std::atomic<size_t> consumed{0};
  auto inner = std::make_unique<CountingSource>(50, &consumed, /*bad=*/17);
  hf::PrefetchingSource source(std::move(inner), 3);
  EXPECT_EQ(source.size(), 50u);
  EXPECT_EQ(source.name(), "counting");
  EXPECT_EQ(source.camera_origin(), "test");
  for (size_t i = 0; i < 50; ++i) {
    const hf::FrameRead r = source.next();
    consumed = i + 1;
    ASSERT_EQ(r.frame.index, i);
    EXPECT_EQ(r.frame.timestamp_s, 0.5 * double(i));
    if (i == 17) {
      EXPECT_EQ(r.status, hf::FrameStatus::bad_frame);
      EXPECT_EQ(r.message, "frame 17: broken");
    } else {
      EXPECT_EQ(r.status, hf::FrameStatus::ok);
    }
  }
  EXPECT_EQ(source.next().status, hf::FrameStatus::end);
  EXPECT_EQ(source.next().status, hf::FrameStatus::end);
}

TEST(Prefetch, LookAheadIsBounded) {
  std::atomic<size_t> consumed{0};
  auto inner = std::make_unique<CountingSource>(100, &consumed);
  CountingSource* raw = inner.get();
  const size_t capacity = 4;
  hf::PrefetchingSource source(std::move(inner), capacity);
  // Without a consumer the thread fills the queue and then waits.
  while (raw->calls_.load() < capacity) std::this_thread::yield();
  for (size_t i = 0; i < 100; ++i) {
    ASSERT_EQ(source.next().frame.index, i);
    consumed = i + 1;
  }
  // The thread calls next() only while the queue has room, so at most `capacity` frames are decoded beyond what
  // the consumer took, plus one if it started its call just before the consumer's counter moved.
  EXPECT_LE(raw->max_ahead_.load(), capacity + 1);
  EXPECT_GE(raw->max_ahead_.load(), capacity);
}

TEST(Prefetch, ExceptionsArriveAfterTheFramesBeforeThem) {
  hf::PrefetchingSource source(std::make_unique<CountingSource>(10, nullptr, size_t(-1), /*throw_at=*/3), 2);
  for (size_t i = 0; i < 3; ++i) EXPECT_EQ(source.next().frame.index, i);
  EXPECT_THROW(source.next(), std::runtime_error);
  EXPECT_EQ(source.next().status, hf::FrameStatus::end);  // the thread stopped; no hang
}

TEST(Prefetch, DestructionStopsAFullOrRunningThread) {
  for (int trial = 0; trial < 20; ++trial) {
    // Never consumed: the thread is blocked on a full queue.
    { hf::PrefetchingSource source(std::make_unique<CountingSource>(1000, nullptr), 2); }
    // Consumed partly, destroyed while the thread may be inside inner->next().
    {
      hf::PrefetchingSource source(std::make_unique<CountingSource>(1000, nullptr), 1);
      for (int i = 0; i < trial; ++i) source.next();
    }
    // Finished source.
    {
      hf::PrefetchingSource source(std::make_unique<CountingSource>(2, nullptr), 8);
      while (source.next().status != hf::FrameStatus::end) {
      }
    }
  }
  SUCCEED();
}

TEST(Prefetch, RejectsNullSourceAndZeroCapacity) {
  EXPECT_THROW(hf::PrefetchingSource(nullptr, 2), hf::Error);
  EXPECT_THROW(hf::PrefetchingSource(std::make_unique<CountingSource>(1, nullptr), 0), hf::Error);
}
