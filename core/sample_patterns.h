// Quasi-random sample patterns for non-uniform image sampling (Siekawa, section 4.1: "quasi-random distribution
// of samples" with a density that falls with the distance from the point of interest).
//
// The pattern is the Halton sequence (bases 2 and 3 for the position, base 5 for acceptance): point k sits at
// (H2(k) width, H3(k) height) and is kept when H5(k) < density at that pixel, so the kept points are
// low-discrepancy in the plane and distributed in proportion to the density, deterministically (no seed: the
// sequence is the pattern; `offset` starts it elsewhere for a different but equally good pattern).
//
// Thread-safety: pure. Errors: hf::Error for a non-positive size, coverage outside [0, 1] or a density image of
// the wrong size.
#pragma once

#include <cstdint>
#include <vector>

#include "core/image.h"

namespace hf {

// The radical inverse of index in `base` (>= 2): the Halton sequence's coordinate, in [0, 1).
double halton(std::uint64_t index, int base);

// A width x height mask (1 = sample) with `coverage` of the pixels set (the first Halton points that land on
// distinct pixels, until round(coverage * width * height) are set).
std::vector<std::uint8_t> halton_mask(int width, int height, double coverage, std::uint64_t offset = 0);

// A mask whose local coverage follows `density` (values in [0, 1], the wanted fraction of sampled pixels there):
// Halton points are drawn until every pixel's acceptance would have been tried about once per pixel of the
// image (width * height draws), each kept where H5(k) < density; pixels with density 1 are then set outright,
// so a full-rate region of interest is sampled densely, exactly.
std::vector<std::uint8_t> halton_mask(const Image<float>& density, std::uint64_t offset = 0);

// The density of a focus + context view: 1 within radius_px of (cx, cy), falling as
// (radius_px / r)^2 outside it (coverage like the retina's receptor density), never below floor.
Image<float> focus_density(int width, int height, float cx, float cy, float radius_px, float floor);

}  // namespace hf
