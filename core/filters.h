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
  float sigma_s_px = 4.5f;  // spatial sigma in pixels (KinectFusion / PCL KinFu / OpenCV KinFu: 4.5)
  float sigma_r_m = 0.03f;  // range sigma in metres (KinectFusion / PCL KinFu: 30 mm)
  // Half window size; 0 = ceil(2 sigma_s_px) (9 for sigma_s 4.5: a 19x19 window, 361 taps). The default, 3 (a 7x7
  // window, 49 taps), is OpenCV KinFu's bilateral_kernel_size = 7 (InfiniTAM filters with 5x5, PCL KinFu with
  // 13x13): the filter runs on every frame, and 7x7 costs 7.4x fewer taps than 19x19. With sigma_s = 4.5 the 7x7
  // spatial weights are all >= 0.64, so the window is close to a box of N_eff ~ 46 samples: it still cuts
  // i.i.d. depth noise by ~6.8x (19x19: ~15x) and keeps edges, since the range term does the edge-preserving.
  int radius_px = 3;
};

// The half window size the filter uses for `params` (radius_px, or ceil(2 sigma_s_px) when radius_px is 0).
int bilateral_radius_px(const BilateralParams& params);

// Edge-preserving smoothing of a depth image (metres, 0 = invalid), KinectFusion eq. 2 over the
// (2 radius + 1)^2 window. Invalid pixels (0, NaN, inf, negative) stay invalid and are written as 0; they carry
// no weight as neighbours. The window is clipped at the border. Same result as hf_bilateral_depth_pixel
// (core/kernels/image_kernels.h, the OpenCL path) up to float rounding: the CPU loop is vectorised across each
// row with a polynomial exp (relative error < 2e-7). Throws hf::Error when sigma_s_px or sigma_r_m is not
// finite and positive or radius_px is outside [0, 1000].
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
