// Structural similarity (Wang, Bovik, Sheikh and Simoncelli 2004, "Image quality assessment: from error
// visibility to structural similarity"), the accuracy measure of Siekawa's reconstructions: for every 11x11
// window (circular-symmetric Gaussian weights, sigma 1.5 px, normalised to sum 1) at which the window lies wholly
// inside the image,
//
//   SSIM(x, y) = (2 mu_x mu_y + C1) (2 sigma_xy + C2) / ((mu_x^2 + mu_y^2 + C1) (sigma_x^2 + sigma_y^2 + C2)),
//   C1 = (K1 L)^2, C2 = (K2 L)^2, K1 = 0.01, K2 = 0.03, L the dynamic range,
//
// and the result is their mean (MSSIM, eq. 17), as in the authors' reference code ('valid' filtering, no
// down-sampling). Moments are accumulated in double.
//
// Failure modes are statuses, mssim = 0: size_mismatch, too_small (an image smaller than one window),
// non_finite (a NaN or inf pixel). Thread-safety: pure.
#pragma once

#include "core/image.h"

namespace hf {

struct SsimOptions {
  double dynamic_range = 1.0;  // L: 1 for intensities in [0, 1], 255 for 8-bit values
  double k1 = 0.01, k2 = 0.03;  // the paper's constants
  int window_px = 11;          // odd
  double sigma_px = 1.5;
};

enum class SsimStatus { ok, size_mismatch, too_small, non_finite };
const char* to_string(SsimStatus status);

struct SsimResult {
  SsimStatus status = SsimStatus::ok;
  double mssim = 0.0;  // in [-1, 1]; 1 only for identical images
  long windows = 0;    // (width - window + 1) * (height - window + 1)
};

// x and y single-channel images of the same size. `map`, when given, receives the per-window SSIM
// ((width - window + 1) x (height - window + 1), the window centred at map pixel + window / 2).
SsimResult ssim(const Image<float>& x, const Image<float>& y, const SsimOptions& options = {},
                Image<float>* map = nullptr);

// Colour images are compared on their BT.601 luma in [0, 1] (intensity_from_color), as Wang et al. do with
// grey-scale images; options.dynamic_range should then stay 1.
SsimResult ssim(const ColorImage& x, const ColorImage& y, const SsimOptions& options = {},
                Image<float>* map = nullptr);

}  // namespace hf
