// Per-pixel filters: the bilateral depth filter (KinectFusion eq. 2), intensity gradients for photometric
// registration, and bilinear sampling with validity.
//
// The per-pixel maths is in core/kernels/image_kernels.h; these are the CPU loops (parallel over rows with TBB,
// deterministic). Pure functions, safe to call from several threads.
#pragma once

#include <optional>

#include "core/image.h"

namespace hf {

struct BilateralParams {
  float sigma_s_px = 4.5f;  // spatial sigma in pixels (KinectFusion / PCL KinFu: 4.5)
  float sigma_r_m = 0.03f;  // range sigma in metres (KinectFusion / PCL KinFu: 30 mm)
  int radius_px = 0;        // half window size; 0 = ceil(2 sigma_s_px) (9 for the default: a 19x19 window)
};

// Edge-preserving smoothing of a depth image (metres, 0 = invalid). Invalid pixels (0, NaN, inf, negative)
// stay invalid and are written as 0; they carry no weight as neighbours. The window is clipped at the border.
// Throws hf::Error when sigma_s_px or sigma_r_m is not finite and positive or radius_px < 0.
DepthImage bilateral_filter_depth(const DepthImage& depth, const BilateralParams& params = {});

// Gradient images (intensity units per pixel; x to the right, y down).
struct ImageGradients {
  Image<float> dx, dy;
};

// Sobel / 8: exact for linear ramps, also at the border (one-sided there); see hf_gradient_pixel.
ImageGradients image_gradients(const Image<float>& image);

// Bilinear interpolation at (x, y), pixel centres at integers. nullopt outside [0, w-1] x [0, h-1] or for NaN
// coordinates.
std::optional<float> sample_bilinear(const Image<float>& image, float x, float y);

// As sample_bilinear, but also nullopt when any tap with non-zero weight is an invalid depth: holes never blend
// into valid depth.
std::optional<float> sample_depth_bilinear(const DepthImage& depth, float x, float y);

}  // namespace hf
