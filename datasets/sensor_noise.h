// Sensor model for synthetic RGB-D frames: what a Kinect-class structured-light camera does to a perfect depth
// map and colour image. Every effect is switchable through NoiseOptions; NoiseOptions::none() turns all off, and
// then the output depth equals the ray-cast depth exactly.
//
// Depth, per output pixel (x, y), in this order:
//  1. Lateral noise (Nguyen et al. 2012): the depth is looked up at the displaced pixel
//       (round(x + sigma_L n_x), round(y + sigma_L n_y)),  sigma_L(theta) = 0.8 + 0.035 theta / (pi/2 - theta) px,
//     n_x, n_y ~ N(0, 1), theta the incidence angle at (x, y). sigma_L is in pixels of a 640-pixel-wide image
//     (the Kinect's) and is scaled by width / 640, so the angular error is the same at any resolution.
//     Nearest-pixel lookup, clamped to the image, so edges move but no "flying pixels" are invented. z0 and theta0 below are the values at the looked-up pixel.
//  2. Range: z0 < min_range_m (0.4) or z0 > max_range_m (4.5) -> missing (0).
//  3. Grazing angles: theta0 > max_incidence_deg (80 deg) -> missing.
//  4. Depth edges: if the looked-up pixel has a 4-neighbour with no surface or with |z_n - z0| > edge_relative_jump
//     * z0 (0.05), the pixel is missing with probability edge_dropout_probability (0.5).
//  5. Holes (off by default; the `holes` preset): a blob mask covering exactly round(hole_fraction * W * H)
//     pixels (the highest values of a two-octave value-noise field with feature size hole_blob_px) is missing.
//  6. Axial noise (Nguyen et al. 2012, eq. for a Kinect v1, theta between the ray and the surface normal):
//       sigma_z(z, theta) = 0.0012 + 0.0019 (z - 0.4)^2 + 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2   [m]
//     z1 = z0 + sigma_z(z0, theta0) n_z, n_z ~ N(0, 1).
//  7. Disparity quantisation (ICL-NUIM, Handa et al. 2014): the Kinect measures disparity in 1/8 pixel steps with
//     focal length x baseline = 585 px x 0.075 m, so the disparity in 1/8-pixel units is D = 351.30 / z (ICL-NUIM
//     writes this 35130 / z with z in centimetres). Optionally (disparity_sigma, default 0) Gaussian noise in
//     those units is added (ICL-NUIM uses 1/6); the result is rounded to an integer and converted back:
//       z2 = 351.30 / round(351.30 / z1 + disparity_sigma n_d).
//     The depth steps are about z^2 / 351.3 m: 2.8 mm at 1 m, 26 mm at 3 m. Because sigma_z already describes the
//     total axial noise, disparity_sigma is 0 by default so the axial noise is not counted twice. For a Gaussian
//     sigma of at least half a step the rounding adds variance step^2 / 12 (Sheppard), so the measured standard
//     deviation is sqrt(sigma_z^2 + step^2 / 12). ICL-NUIM's intermediate rounding to whole centimetres is an
//     artefact of its storage and is not modelled.
//
// Colour: each channel of the (exposure-scaled) linear colour in [0, 1] becomes round(255 c + colour_sigma n),
// clamped to [0, 255], n ~ N(0, 1) independent per channel and pixel.
//
// Determinism: all random numbers come from Rng (std::mt19937_64 with a fixed seeding scheme and our own uniform
// and inverse-CDF normal transforms), seeded per (seed, frame, stream, image row). Every depth pixel draws the
// same fixed set of numbers whichever effects are enabled, so a frame is bit-identical on every platform and
// standard library, independent of thread count, and switching one effect off leaves the others' realisation
// unchanged.
#pragma once

#include <cstdint>
#include <random>

#include "core/image.h"

namespace hf::datasets {

// Linear RGB, float, the renderer's colour before exposure and 8-bit conversion.
struct RgbF {
  float r = 0.0f, g = 0.0f, b = 0.0f;
};
using ColorImageF = Image<RgbF>;

// mt19937_64 with library-independent uniform and normal transforms.
// Phi^-1(p), the standard normal quantile, to double precision (Acklam's approximation + one Halley step).
double inverse_normal_cdf(double p);

class Rng {
 public:
  // Seeds from a splitmix64 hash of all four numbers, so nearby seeds give unrelated streams.
  Rng(std::uint64_t seed, std::uint64_t frame, std::uint64_t stream, std::uint64_t row = 0);
  double uniform();  // [0, 1), 53 random bits
  // N(0, 1) by inversion: each 64-bit draw gives two samples, each through a 2^16-entry table of the inverse
  // normal CDF with linear interpolation (range +-4.17 sigma; the variance is 1 - 5e-4 of a true normal's).
  double normal();

 private:
  std::mt19937_64 engine_;
  double spare_ = 0.0;
  bool has_spare_ = false;
};

struct NoiseOptions {
  bool lateral = true;
  bool axial = true;
  bool quantisation = true;
  double disparity_sigma = 0.0;           // extra disparity noise, 1/8-pixel units (ICL-NUIM: 1/6)
  double min_range_m = 0.4;               // nearer -> missing
  double max_range_m = 4.5;               // farther -> missing
  double max_incidence_deg = 80.0;        // grazing -> missing
  double edge_dropout_probability = 0.5;  // at depth discontinuities
  double edge_relative_jump = 0.05;       // a discontinuity: |dz| > this * z between 4-neighbours
  double hole_fraction = 0.0;             // blob holes, fraction of all pixels (the `holes` preset: 0.3)
  double hole_blob_px = 24.0;             // blob feature size, pixels at 640 px width (scaled with width)
  double colour_sigma = 2.0;              // per channel, 8-bit units

  // Everything off: depth = ray-cast depth, colour = exposure-scaled colour rounded to 8 bits.
  static NoiseOptions none();
  bool depth_noise_enabled() const;
  // Throws hf::Error naming the first bad field (negative sigma, probability outside [0, 1], ...).
  void validate() const;
};

// The model's standard deviations (see the top of this file). theta in radians, clamped below pi/2.
double axial_sigma_m(double z_m, double theta_rad);
double lateral_sigma_px(double theta_rad);
// Disparity quantisation: constant, the depth after rounding, and the local step dz/dD = z^2 / 351.30.
constexpr double kDisparityConstant = 351.30;  // (1/8 px) * m: 585 px * 0.075 m * 8
double quantise_depth_m(double z_m);
double quantisation_step_m(double z_m);

// Applies steps 1-7 to a ray-cast depth map. incidence_rad holds theta per pixel (ignored where depth is 0).
// The images must have the same size; the result has it too. Parallel over rows; deterministic.
DepthImage apply_depth_noise(const DepthImage& clean_depth, const Image<float>& incidence_rad,
                             const NoiseOptions& options, std::uint64_t seed, std::uint64_t frame);

// The hole mask of step 5 (1 = missing) for a width x height image: exactly round(fraction * W * H) pixels set.
Image<std::uint8_t> hole_mask(int width, int height, double fraction, double blob_px, std::uint64_t seed,
                              std::uint64_t frame);

// Colour: c * gain per channel, then 8-bit conversion with Gaussian noise (colour_sigma, 0 = none).
ColorImage finish_colour(const ColorImageF& linear, double gain, double colour_sigma, std::uint64_t seed,
                         std::uint64_t frame);

}  // namespace hf::datasets
