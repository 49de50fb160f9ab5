// Synthetic RGB-D sequences with exact ground truth, rendered in process (no disk): the frames the `generate`
// command writes and the `synthetic:PRESET` input reads.
//
//   SyntheticOptions options;           // preset "room", 300 frames, seed 0, 640x480 "ros" camera, noise on
//   options.preset = "sphere";
//   SyntheticSequence seq(options);     // throws hf::Error for an unknown preset or bad options
//   SyntheticFrame f = seq.frame(17);   // any frame, in any order: frame i depends only on (options, i)
//   double d = seq.scene().sdf(p_world);
//
// Time stamps: frame i is at round(1e6 * i / 30) microseconds (30 Hz, exactly representable in the 6-decimal TUM
// text files). Poses: T_world_camera (camera to world), world z up, metres.
// Thread-safety: frame() and the accessors are const and may be called concurrently; frame() itself renders in
// parallel over rows (TBB).
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "datasets/presets.h"
#include "datasets/scene.h"
#include "datasets/sensor_noise.h"

namespace hf::datasets {

struct SyntheticOptions {
  std::string preset = "room";  // see datasets/presets.h; preset_names() lists them
  int frames = 300;             // size() of the sequence; 1 .. 1'000'000
  std::uint64_t seed = 0;       // sensor-noise and exposure-jitter realisation
  // Resolution and intrinsics; a smaller camera (e.g. PinholeCamera::preset("ros").scaled(2)) renders faster.
  PinholeCamera camera = PinholeCamera::preset("ros");
  bool noise_enabled = true;           // false: NoiseOptions::none() (depth == depth_clean, no colour noise)
  std::optional<NoiseOptions> noise;   // overrides the preset's noise defaults when set (and noise_enabled)
  double frame_rate_hz = 30.0;

  // Throws hf::Error naming the bad field.
  void validate() const;
};

struct SyntheticFrame {
  int index = 0;
  double timestamp_s = 0.0;
  DepthImage depth;        // with the sensor model applied; metres, 0 = missing
  DepthImage depth_clean;  // exact ray-cast depth; 0 = no surface
  ColorImage color;        // RGB8 with exposure gain and colour noise
  SE3 T_world_camera;      // ground truth
  double gain = 1.0;       // the colour gain used (exposure preset)
};

class SyntheticSequence {
 public:
  explicit SyntheticSequence(const SyntheticOptions& options);

  int size() const { return options_.frames; }
  // Renders frame i (0 <= i < size(), else hf::Error). Deterministic in (options, i).
  SyntheticFrame frame(int i) const;

  const PinholeCamera& camera() const { return options_.camera; }
  SE3 T_world_camera(int i) const;
  double timestamp_s(int i) const;
  const Scene& scene() const { return preset_.scene; }
  const Preset& preset() const { return preset_; }
  const NoiseOptions& noise() const { return noise_; }
  const SyntheticOptions& options() const { return options_; }

 private:
  void check_index(int i) const;

  SyntheticOptions options_;
  Preset preset_;
  NoiseOptions noise_;
};

}  // namespace hf::datasets
