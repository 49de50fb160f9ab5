// The shaded render for people with fewer rays (issue 19): cast a subset of the rays of a camera and reconstruct
// the full image from them, after Popescu et al.'s focus + context CoNUS views and Siekawa's reconstruction from
// non-uniform samples (core/sampling_map.h, core/push_pull.h, core/mesh_interpolation.h, core/sample_patterns.h).
//
//   // Siekawa: any sample mask (e.g. halton_mask(focus_density(...))), reconstructed by push-pull or the mesh
//   SparseRender a = render_masked(grid, camera, T_world_camera, options, mask, Reconstruction::push_pull);
//   // Popescu: full rate in a region of interest, 1 / 2^context_level per axis around it
//   SparseRender b = render_focus_context(grid, camera, T_world_camera, options, {x0, y0, x1, y1}, 2);
//   // Popescu: a CoNUS image through a sampling map, resampled to the uniform image
//   SparseRender c = render_conus(grid, camera, T_world_camera, options, SamplingMap::from_region_rates(...));
//
// render_masked casts through fusion/raycast_sampled.h (rays at the mask's pixels only); a ray that misses the
// model is a sample too (black background), so silhouettes stay where they are. render_focus_context casts two
// pinhole cameras through raycast(): the region of interest as a crop of `camera` (same focal length and centre
// of projection, principal point shifted) at full rate, and the whole view at camera.scaled(context_level); the
// context is resampled to every pixel bilinearly (the paper's Figure 8 resampling, for this piecewise-constant
// sampling map) and the region of interest written over it. Both cameras share the centre of projection, so
// straight lines stay connected across the region's border (coherent sampling). render_conus casts, through
// raycast_sampled, the pixel nearest each CoNUS pixel's ray (SamplingMap::rays, the paper's Figure 5), fills the
// CoNUS image from them and resamples the uniform image from it (from_conus, the paper's Figure 8); rays are
// snapped to pixel centres because raycast_sampled casts at pixels, so the view is coherent to half a pixel.
//
// Outputs: `shaded` is camera-sized grey head-light shading as RaycastResult::shaded (options.shade is forced on);
// `rays` is the number of rays cast; cast_ms and reconstruct_ms are wall times of the two stages. Frames, units
// and thread-safety as raycast() (fusion/raycast.h); the grid must not change during the call. Errors: hf::Error
// for a mask of the wrong size, an empty or out-of-image region, context_level outside [1, 4].
#pragma once

#include <cstdint>

#include "core/camera.h"
#include "core/image.h"
#include "core/push_pull.h"
#include "core/sampling_map.h"
#include "core/se3.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

enum class Reconstruction { push_pull, mesh };

struct SparseRender {
  ColorImage shaded;
  long rays = 0;
  double cast_ms = 0.0, reconstruct_ms = 0.0;
  PushPullResult fill;  // the reconstruction's status and counts (render_masked)
  Image<float> conus;   // render_conus: the CoNUS image itself (grey, conus_width x conus_height)
};

SparseRender render_masked(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                           RaycastOptions options, const Image<std::uint8_t>& rays, Reconstruction method);

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;  // [x0, x1) x [y0, y1), pixels
};

SparseRender render_focus_context(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                                  RaycastOptions options, const PixelRect& roi, int context_level);

// map.width() x map.height() must be the camera's size (else hf::Error).
SparseRender render_conus(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                          RaycastOptions options, const SamplingMap& map);

}  // namespace hf::fusion
