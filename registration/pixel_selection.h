// Which current-frame pixels give registration rows: all of them, an importance-driven few per tile, or the same
// number spread uniformly (issue 19, "fewer rays"; the per-tile budget of DSO, Engel et al. 2018, section 3.2).
//
//   hf::PixelSelectionOptions o{.mode = hf::PixelSelectionMode::importance, .tile_px = 16, .budget_per_tile = 32};
//   const hf::Image<std::uint8_t> mask = hf::select_pixels(level, o);  // 1 = gives rows
//   hf::apply_pixel_selection(mask, &vertices);                         // w = 0 elsewhere
//
// The result is a per-pixel mask, applied by invalidating the vertices of the pixels left out. Every per-pixel
// kernel already skips an invalid current vertex, so the rows are the selected pixels' on every reduction backend
// (cpu, AVX2, OpenCL) without a kernel reading the mask. The Gauss-Newton driver applies it per level
// (GaussNewtonOptions::row_selection); the SLAM pipeline's sampled tracking raycast casts the rays of the same mask
// (fusion/raycast_sampled.h).
//
// Importance (pixel_importance): |grad I| (intensity units per pixel, the level's Sobel / 8 gradients) plus
// depth_edge_weight times the largest relative depth step to a valid 4-neighbour, |z_q - z_p| / z_p (capped at 1).
// The first carries the photometric rows' information (their Jacobian is linear in grad I), the second marks depth
// edges and creases where point-to-plane rows see the normals change. A level without intensity scores depth only.
//
// Per tile of tile_px x tile_px pixels: when it holds at most budget_per_tile valid pixels (vertex w != 0), all of
// them; otherwise the budget_per_tile of highest importance (importance mode) or of lowest ordered-dither rank
// (uniform mode). Ties in importance go by the same rank, the Bayer matrix of the tile: its first quarter is the
// even-x, even-y lattice, its first sixteenth every fourth pixel, so a flat tile gets the uniform pattern and the
// two modes select the SAME NUMBER of pixels in every tile (the comparison bench/results/fewer_rays_tracking.md
// makes). Deterministic: no randomness, no dependence on the thread count.
#pragma once

#include <cstdint>

#include "core/image.h"
#include "registration/frame_pyramid.h"

namespace hf {

enum class PixelSelectionMode {
  all = 0,         // every pixel gives rows (no mask)
  importance = 1,  // the budget per tile by pixel_importance
  uniform = 2,     // the budget per tile by ordered-dither rank only (the equal-count baseline)
};

struct PixelSelectionOptions {
  PixelSelectionMode mode = PixelSelectionMode::all;
  int tile_px = 16;           // tile side in pixels: a power of two in [2, 64]
  int budget_per_tile = 64;   // pixels kept per tile, 1 .. tile_px^2 (64 of 256 = a quarter)
  float depth_edge_weight = 4.0f;  // weight of the relative depth step against |grad I| (a 5 cm step at 2 m: 0.1)
  // Levels 0 .. levels - 1 (0 finest) are selected; coarser levels keep every pixel (they are cheap and give the
  // coarse alignment its basin).
  int levels = 1;

  bool enabled() const { return mode != PixelSelectionMode::all; }
  // Throws hf::Error "registration options: row_selection_<field> ..." naming the first bad field.
  void validate() const;
};

// Importance per pixel (see above); 0 where the vertex is invalid.
Image<float> pixel_importance(const FramePyramidLevel& level, float depth_edge_weight);

// The mask (1 = selected) of `level` under `options` (mode all: every valid pixel). Throws hf::Error for invalid
// options.
Image<std::uint8_t> select_pixels(const FramePyramidLevel& level, const PixelSelectionOptions& options);

// Invalidates (w = 0, the vertex becomes hf_invalid4()) every vertex whose mask pixel is 0. hf::Error when the sizes
// differ.
void apply_pixel_selection(const Image<std::uint8_t>& mask, VertexMap* vertices);

// The rank of pixel (x, y) of a tile_px x tile_px tile in the tile's ordered-dither (Bayer) order, 0 .. tile_px^2 - 1.
int dither_rank(int x, int y, int tile_px);

}  // namespace hf
