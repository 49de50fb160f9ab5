// The fusion benchmarks' input: every 4th frame (7.5 Hz of motion) of the `room` preset at 640x480 with its sensor
// noise, kRoomFrames of them, rendered once per process.
#pragma once

#include <vector>

#include "core/camera.h"
#include "datasets/synthetic_sequence.h"

namespace hf::bench {

inline constexpr int kRoomFrames = 24;

inline const std::vector<datasets::SyntheticFrame>& room_frames() {
  static const std::vector<datasets::SyntheticFrame> frames = [] {
    datasets::SyntheticOptions options;
    options.preset = "room";
    options.frames = 300;
    const datasets::SyntheticSequence seq(options);
    std::vector<datasets::SyntheticFrame> out;
    for (int i = 0; i < kRoomFrames; ++i) out.push_back(seq.frame(i * 4));
    return out;
  }();
  return frames;
}

inline const PinholeCamera& room_camera() {
  static const PinholeCamera camera = PinholeCamera::preset("ros");
  return camera;
}

}  // namespace hf::bench
