// Push-pull fill (Siekawa, "Image Reconstruction from Spatially Non-uniform Samples", section 3.1): the pixels
// of an image that hold no sample take the value of the nearest coarser pyramid level that has one.
//
//   push: 2x2 masked averages, level by level, to the coarsest level (1x1, or options.max_levels steps);
//   pull: from the second-coarsest level down to level 0, an empty pixel takes its parent's value.
//
// The per-pixel maths is core/kernels/push_pull_kernels.h, shared with the OpenCL path
// (core/opencl/push_pull_opencl.h), which gives the same result to float rounding.
//
// Inputs: `values` holds width * height * channels floats (channels 1..4 interleaved, row-major), `mask` width *
// height bytes, non-zero where a pixel is a sample. Both are updated in place: on return mask is 1 wherever a
// pixel holds a value (sampled or filled) and 0 where it is still empty (value 0). A masked pixel with a NaN or
// inf channel is not a sample (counted in dropped_non_finite). No NaN or inf is ever written.
//
// Failure modes are statuses, never exceptions: empty_image (width or height < 1, or null pointers),
// bad_channels (channels outside 1..4), no_samples (nothing to fill from: every value set to 0, mask 0).
// Thread-safety: pure; each call parallelises over rows internally and is deterministic.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"

namespace hf {

enum class PushPullStatus {
  ok,                  // every empty pixel that a sample reaches was filled
  dropped_non_finite,  // as ok, but some masked pixels had NaN / inf channels and were treated as empty
  no_samples,          // no sample at all: nothing filled, every value 0
  empty_image,         // width or height < 1 (or null buffers): nothing done
  bad_channels,        // channels not in 1..4: nothing done
};

const char* to_string(PushPullStatus status);

// Whether the status means the image was filled (ok or dropped_non_finite).
inline bool push_pull_filled(PushPullStatus status) {
  return status == PushPullStatus::ok || status == PushPullStatus::dropped_non_finite;
}

struct PushPullOptions {
  // Push steps at most; -1 = until the level is 1x1 (every pixel filled when the image has one sample). With
  // L >= 0 an empty pixel is filled only when its aligned 2^L x 2^L block (or a smaller one) holds a sample, so
  // holes wider than about 2^L pixels stay empty: "small holes only".
  int max_levels = -1;
};

struct PushPullResult {
  PushPullStatus status = PushPullStatus::ok;
  int levels = 0;                // push steps taken (0 for a 1x1 image)
  long filled_pixels = 0;        // pixels empty on input (or dropped) that now hold a value
  long empty_pixels = 0;         // pixels still empty on return (mask 0, value 0)
  long dropped_non_finite = 0;   // masked pixels with a NaN / inf channel
};

// Width and height of levels 0..L of a push-pull pyramid over a width x height image (each level ceil-halved, L
// the number of push steps options.max_levels allows, stopping at 1x1). Shared by the C++ and OpenCL paths.
struct PushPullLevel {
  int width = 0, height = 0;
};
std::vector<PushPullLevel> push_pull_levels(int width, int height, const PushPullOptions& options);

PushPullResult push_pull_fill(int width, int height, int channels, float* values, std::uint8_t* mask,
                              const PushPullOptions& options = {});

// The stages every path shares around its push and pull. push_pull_prepare checks the arguments and prepares
// level 0 in place (hf_push_pull_prepare_pixel); its status is final unless push_pull_filled(status), and
// *samples is the number of samples. push_pull_finish counts filled and empty pixels on level 0's mask.
PushPullResult push_pull_prepare(int width, int height, int channels, float* values, std::uint8_t* mask,
                                 long* samples);
void push_pull_finish(const std::uint8_t* mask, long pixels, long samples, PushPullResult* result);

// Depth in metres: valid depths (finite, > 0) are the samples; holes are filled with averaged depths of their
// neighbourhood, pixels that stay empty are 0. Meant for the tracking pyramid's input, never for integration.
PushPullResult push_pull_fill_depth(DepthImage& depth, const PushPullOptions& options = {});

}  // namespace hf
