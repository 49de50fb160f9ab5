// Normalised thumbnails: the small images the `thumbnail` and `eigenspaces` appearance codes are built from.
//
// A thumbnail is the concatenation of two parts of width x height cells each, one value per cell:
//   intensity  block average of BT.601 luma (core/image.h), minus its mean, divided by its norm (unit norm);
//   depth      block average of the valid depth (finite, > 0) in metres, cells without depth set to the mean of the
//              valid cells, minus that mean, divided by its norm, times depth_weight.
// So ||a - b||^2 = ||intensity_a - intensity_b||^2 + depth_weight^2 ||depth_a - depth_b||^2, each term in [0, 4].
// A part without information (empty or constant image: a black frame, no valid depth) is all zeros, so it adds a
// constant to every distance instead of a NaN. The mean and norm removal make the code invariant to a global
// gain and offset of brightness (auto-exposure) and to a global depth offset/scale.
// Cells map to pixels by x_cell = x * width / image_width (any image size; an image smaller than the thumbnail
// leaves some cells empty, treated as missing).
#pragma once

#include <vector>

#include "core/image.h"

namespace hf::slam {

struct ThumbnailOptions {
  // Cells per part (640x480 -> 32x32 pixel blocks). 20x15 retrieved as well as 40x30 on the tuning part at a
  // quarter of the memory (bench/results/appearance.tuning.md).
  int width = 20, height = 15;
  double depth_weight = 1.0;    // weight of the depth part; 0 = intensity only (the depth part is then left out)
  // Throws hf::Error naming the bad field (sizes 1..256, weight finite and >= 0).
  void validate() const;
  // Length of make_thumbnail's vector: width * height, twice that when depth_weight > 0.
  size_t length() const;
};

std::vector<float> make_thumbnail(const ColorImage& colour, const DepthImage& depth, const ThumbnailOptions& options);

// Squared Euclidean distance in double (finite for finite inputs). Vectors of equal length.
double squared_distance(const float* a, const float* b, size_t n);

}  // namespace hf::slam
