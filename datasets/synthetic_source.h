// A FrameSource (io/frame_source.h) over a synthetic sequence, so `synthetic:PRESET` works wherever a dataset
// folder does. Frames are rendered on demand in next() (no disk); every frame is ok and carries its ground-truth
// pose; ground_truth() holds the whole trajectory.
#pragma once

#include <memory>
#include <string>

#include "datasets/synthetic_sequence.h"
#include "io/frame_source.h"

namespace hf::datasets {

inline constexpr const char* kSyntheticPrefix = "synthetic:";

// Opens preset `preset` with `options` (options.preset is replaced by `preset`). Throws hf::Error for an unknown
// preset (listing the known ones) or bad options.
std::unique_ptr<FrameSource> open_synthetic(const std::string& preset, SyntheticOptions options = {});

// True for inputs of the form "synthetic:PRESET".
bool is_synthetic_input(const std::string& input);
// Opens "synthetic:PRESET"; throws hf::Error when `input` is not of that form or the preset is unknown.
std::unique_ptr<FrameSource> open_synthetic_input(const std::string& input, SyntheticOptions options = {});

}  // namespace hf::datasets
