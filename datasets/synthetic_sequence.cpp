#include "datasets/synthetic_sequence.h"

#include <cmath>

#include "core/error.h"
#include "datasets/renderer.h"

namespace hf::datasets {

void SyntheticOptions::validate() const {
  if (frames <= 0 || frames > 1'000'000)
    throw Error("synthetic sequence: expected frames in 1..1000000, got " + std::to_string(frames));
  if (!(frame_rate_hz > 0.0) || !std::isfinite(frame_rate_hz))
    throw Error("synthetic sequence: expected a positive frame rate");
  const PinholeCamera& c = camera;
  if (!(c.fx > 0.0 && c.fy > 0.0) || !std::isfinite(c.fx) || !std::isfinite(c.fy) || !std::isfinite(c.cx) ||
      !std::isfinite(c.cy) || c.width <= 0 || c.height <= 0 || c.width > 16384 || c.height > 16384)
    throw Error("synthetic sequence: expected a valid camera, got " + c.describe());
  if (noise) noise->validate();
}

SyntheticSequence::SyntheticSequence(const SyntheticOptions& options)
    : options_(options), preset_(make_preset(options.preset)) {
  options_.validate();
  noise_ = !options_.noise_enabled ? NoiseOptions::none() : options_.noise ? *options_.noise : preset_.noise;
}

void SyntheticSequence::check_index(int i) const {
  if (i < 0 || i >= options_.frames)
    throw Error("synthetic sequence '" + options_.preset + "': frame " + std::to_string(i) + " out of range 0.." +
                std::to_string(options_.frames - 1));
}

double SyntheticSequence::timestamp_s(int i) const {
  // Divide (correctly rounded) rather than multiply by 1e-6, so the stamp is the double nearest to its 6-decimal text.
  return std::round(1e6 * double(i) / options_.frame_rate_hz) / 1e6;
}

SE3 SyntheticSequence::T_world_camera(int i) const {
  check_index(i);
  return preset_.T_world_camera(i);
}

SyntheticFrame SyntheticSequence::frame(int i) const {
  check_index(i);
  SyntheticFrame f;
  f.index = i;
  f.timestamp_s = timestamp_s(i);
  f.T_world_camera = preset_.T_world_camera(i);
  const RenderedView view = render_view(preset_.scene, options_.camera, f.T_world_camera, preset_.lighting);
  f.depth = apply_depth_noise(view.depth, view.incidence_rad, noise_, options_.seed, std::uint64_t(i));
  f.depth_clean = view.depth;
  f.gain = preset_.gain(options_.seed, i);
  const ColorImageF* colour = &view.color;
  RenderedView colour_view;
  if (!preset_.colour_registered()) {
    PinholeCamera colour_camera = options_.camera;
    colour_camera.fx *= preset_.colour_focal_scale;
    colour_camera.fy *= preset_.colour_focal_scale;
    colour_view = render_view(preset_.scene, colour_camera, f.T_world_camera * preset_.T_depth_colour,
                              preset_.lighting);
    colour = &colour_view.color;
  }
  f.color = finish_colour(*colour, f.gain, noise_.colour_sigma, options_.seed, std::uint64_t(i));
  return f;
}

}  // namespace hf::datasets
