// The CPU loops of integrate() (fusion/integrate.h), each in two spellings that give the same bits: the plain loop
// (the specification, and the path on processors without AVX2) and an AVX2 one, chosen by hf::cpu_has_avx2()
// (core/simd_avx2.h); tests/fusion/test_integrate_cpu.cpp holds each pair to each other.
//
// Phase 1, per depth row: where each pixel's truncation band starts and ends, in block units (band_row).
//
// Phase 2, per block: the update of one voxel block by one frame, the shared per-voxel kernel (hf_voxel_pixel,
// then hf_integrate_voxel_at of fusion/kernels/integrate_kernels.h) on its 512 voxels (update_block); the AVX2
// spelling takes one block row of eight voxels per step. Its inverse (deintegrate_block) has both spellings too.
//
// Why second spellings: the per-voxel kernel is branchy (outside the image, no depth, hidden, colour or not) and
// gcc does not vectorise it; a block row is exactly eight floats of AVX2 and its eight voxels one 64-byte cache
// line, and the branches become lane masks. In phase 1, the baseline x86-64 build has no rounding instruction, so
// each of a pixel's six floor() calls was a dozen instructions. Both AVX2 loops keep the plain loops' operations
// in the same order without fused multiply-adds (the file is compiled with -ffp-contract=off).
//
// Block geometry: voxel (x, y, z) of the block has its centre at p0 + x s_x + y s_y + z s_z in the camera frame
// (metres), evaluated as (p0 + z s_z + y s_y) + x s_x per component, left to right: s_* are the camera-frame
// images of one voxel step along the world axes.
#pragma once

#include <cstdint>

#include "fusion/kernels/integrate_kernels.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion::detail {

// Phase 1. Pixel u of a depth row with depth d (metres) in [min_depth_m, max_depth_m] (false for NaN) bands the
// segment of its viewing ray from depth z0 = max(d - mu, 1 mm) to z1 = d + mu. In block units (world / block_m):
//   a = (R (ray z0) + t) / block_m,   b = (R (ray z1) + t) / block_m,   ray = (ray_x[u], ray_y, 1),
// each component summed left to right, (R_i0 x + R_i1 y) + R_i2 z + t_i, then multiplied by inv_block. ok[u] is 1
// when the pixel's depth is in range and all six coordinates lie strictly within +-(2^20 - 2) blocks (the range
// the block keys pack), else 0; cell_a / cell_b are floor(a) / floor(b) where ok (undefined elsewhere).
struct BandFrame {
  double R[9];  // T_world_camera's rotation, row-major
  double t[3];
  double inv_block = 0.0, mu = 0.0, min_depth_m = 0.0, max_depth_m = 0.0;
};
struct BandRow {  // width entries each; a[0] holds the x coordinates, a[1] y, a[2] z, likewise the rest
  double* a[3];
  double* b[3];
  std::int32_t* cell_a[3];
  std::int32_t* cell_b[3];
  std::uint8_t* ok;
};
void band_row(const float* depth, int width, const double* ray_x, double ray_y, const BandFrame& f,
              const BandRow& out);
void band_row_avx2(const float* depth, int width, const double* ray_x, double ray_y, const BandFrame& f,
                   const BandRow& out);

// What a frame brings to every block: its depth (metres, row-major K.width x K.height, 0 = none), the optional
// point-to-plane factors (nullptr = projective) and colour (3 bytes per pixel, nullptr = none), truncation mu
// (metres), the weight cap and the observation weight. mu_scale: nullptr (every band mu) or the per-pixel
// truncation scale of IntegrateParams::truncation_depth_ref_m (hf_truncation_scale); only the plain loops read it
// (integrate() takes them when it is set; the AVX2 spellings throw hf::Error).
struct FrameInputs {
  const float* depth = nullptr;
  const float* incidence = nullptr;
  const float* mu_scale = nullptr;
  const float* w_scale = nullptr;  // nullptr or hf_weight_scale per pixel (weight_depth_ref_m); plain loops only
  const hf_uint8* rgb = nullptr;
  hf_intrinsics K{};
  float mu = 0.0f;
  float max_weight = 0.0f;
  float w = 0.0f;
};

// Voxel centre steps of one block in the camera frame.
struct BlockFrame {
  float p0[3];  // centre of voxel (0, 0, 0)
  float s_x[3], s_y[3], s_z[3];
};

// Both return the number of voxels updated (observed by the frame), and set *wrote_surface to whether one of them
// now holds sdf <= 0 (what VoxelBlockGrid::surface_free summarises: integrate() then need not scan the block).
int update_block(Voxel* voxels, const BlockFrame& b, const FrameInputs& in, bool* wrote_surface);
// Only where hf::cpu_has_avx2() (core/simd_avx2.h) and the image has at least two pixels (the colour gather reads
// one byte before the pixel's three); throws hf::Error in a build without the AVX2 path.
int update_block_avx2(Voxel* voxels, const BlockFrame& b, const FrameInputs& in, bool* wrote_surface);

// deintegrate()'s loop (fusion/deintegrate.h): hf_deintegrate_voxel_at on the voxels update_block would update, with
// the same projections (so the same observations, bit for bit). Both spellings return the number of voxels they
// took an observation out of; the AVX2 one has update_block_avx2's preconditions.
int deintegrate_block(Voxel* voxels, const BlockFrame& b, const FrameInputs& in);
int deintegrate_block_avx2(Voxel* voxels, const BlockFrame& b, const FrameInputs& in);

}  // namespace hf::fusion::detail
