// Pairing a depth stream with a colour stream by their time stamps, for back-ends whose two streams arrive
// separately (OpenNI2's two sensors, two V4L2 nodes).
//
// The last `history` frames of each stream are held, because the two streams reach us with different latencies
// (a frame of one may arrive several frames after its partner of the other). A depth and a colour frame whose
// stamps differ by at most max_difference_s make a CapturedFrame stamped with the colour stamp (the image the pose
// is evaluated at, as in TUM); the closest such pair, oldest first, is taken, and every held frame older than it
// is discarded (counted): frames are never paired out of order. Not thread-safe (one capture thread).
#pragma once

#include <deque>
#include <optional>

#include "io/live_source.h"

namespace hf {

class StampPairer {
 public:
  // history: frames held per stream, 8 = a quarter second at 30 Hz of latency difference.
  explicit StampPairer(double max_difference_s, size_t history = 8)
      : max_difference_s_(max_difference_s), history_(history < 1 ? 1 : history) {}
  void offer_depth(double stamp_s, DepthImage depth);
  void offer_color(double stamp_s, ColorImage color);
  // The next pair when the held frames contain one (removing it and everything older), else nullopt.
  std::optional<CapturedFrame> take();
  bool holds_depth() const { return !depth_.empty(); }
  size_t discarded() const { return discarded_; }  // frames that found no partner

 private:
  template <class T>
  struct Held {
    double stamp_s;
    T image;
  };
  double max_difference_s_;
  size_t history_;
  std::deque<Held<DepthImage>> depth_;
  std::deque<Held<ColorImage>> color_;
  size_t discarded_ = 0;
};

}  // namespace hf
