// Image pyramids: Gaussian for intensity, depth-aware for depth (KinectFusion section 3.2).
//
// Geometry: every level halves width and height (rounding down, like hf::PinholeCamera::scaled()), and pixel
// (x, y) of level l+1 covers pixels {2x, 2x+1} x {2y, 2y+1} of level l. Use camera.scaled(l) for level l.
// The per-pixel maths is in core/kernels/image_kernels.h (hf_pyrdown_gaussian_pixel, hf_pyrdown_depth_pixel).
//
// Thread-safety: pure functions; each call parallelises over rows internally (TBB) and is deterministic.
// Errors: hf::Error when an image is smaller than 2x2 (cannot be halved), levels < 1, or a parameter is not
// finite and positive.
#pragma once

#include <vector>

#include "core/image.h"

namespace hf {

// Default sigma_r of the depth-aware pyramid: 3 sigma_r = 9 cm is the window PCL's KinFu uses (30 mm sigma) and
// spans about 3.5 standard deviations of Kinect noise at 4 m (sigma(z) ~ 0.0012 + 0.0019 (z - 0.4)^2 m, Nguyen
// et al. 2012), while any depth step larger than 9 cm is kept as an edge.
inline constexpr float kDepthPyramidSigmaR_m = 0.03f;

// Half-size Gaussian level: 5x5 binomial [1 4 6 4 1]/16 blur plus 2x2 decimation (one 6x6 [1 5 10 10 5 1]/32
// separable kernel), borders clamped. Works for any float image (intensity, gradients).
Image<float> pyr_down_gaussian(const Image<float>& src);

// levels >= 1 images, [0] a copy of level0, [l] = pyr_down_gaussian([l-1]).
std::vector<Image<float>> build_gaussian_pyramid(const Image<float>& level0, int levels);

// Half-size depth level: weighted mean over the 6x6 window of the valid depths within 3 sigma_r_m of the 2x2
// block's lower-median depth; 0 (invalid) where the whole block is invalid. Never mixes surfaces more than
// 3 sigma_r_m apart. NaN/inf/negative input depths count as invalid.
DepthImage pyr_down_depth(const DepthImage& src, float sigma_r_m = kDepthPyramidSigmaR_m);

// levels >= 1 images, [0] a copy of level0, [l] = pyr_down_depth([l-1], sigma_r_m).
std::vector<DepthImage> build_depth_pyramid(const DepthImage& level0, int levels,
                                            float sigma_r_m = kDepthPyramidSigmaR_m);

}  // namespace hf
