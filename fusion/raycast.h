// Raycasting the TSDF: the model image that frame-to-model tracking aligns against, and a shaded render for people.
//
//   RaycastResult r = raycast(grid, camera, T_world_camera);   // vertex/normal/colour/depth maps, camera frame
//
// Per pixel (KinectFusion / InfiniTAM / Niessner et al. 2013): the ray from the camera centre through the pixel
// centre is marched within [min_depth_m, max_depth_m], narrowed to the depth range of the allocated blocks its 8 x 8
// pixel tile sees (InfiniTAM's range image; blocks are clipped against the near plane before they are projected).
// Where the block containing the ray point does not exist the ray jumps to where it leaves that block, or the whole
// 4 x 4 x 4-block region when that holds no block (free and unseen space are never stepped through voxel by voxel); an
// allocated block without surface (no observed voxel with sdf <= 0: VoxelBlockGrid::surface_free) is crossed in one
// step too. Inside allocated blocks, where the nearest voxel is far in front of the surface (sdf > 0.5) the ray
// advances by step_fraction of the distance bound sdf * mu - sqrt(3)/2 voxel without interpolating; nearer the
// surface it takes steps of step_fraction * sdf * mu (at least min_step_vox voxels), sampling the trilinearly
// interpolated SDF. The first sign change from + to - is the surface (a change from - to +, seen when a ray leaves
// the back of a surface, is ignored); the crossing is refined by linear interpolation of the two bracketing samples,
// then Illinois regula falsi on the same bracket until it, or the step the last sample predicts, is below
// refine_tol_vox (0.001 voxel by default). Normals are the normalised SDF gradient by central differences of
// trilinear samples one voxel apart (taken from one gathered neighbourhood of 32 voxels, VolumeSampler::normal);
// colour is trilinear. With RaycastOptions::depth_hint (the depth just integrated from the same pose, as a SLAM
// pipeline has it) each ray first searches a narrow bracket around the hinted depth.
//
// Outputs are in the CAMERA frame (x right, y down, z forward, metres); depth is z along the optical axis, like a
// depth image. Pixels without a hit have depth 0, vertex/normal w = 0, colour black. A hit whose gradient cannot
// be taken (a neighbouring sample unobserved) keeps its vertex and gets an invalid normal.
//
// A sample is valid only when its eight voxels are observed (weight > 0 and >= min_weight); invalid samples are
// stepped over one voxel at a time and break a + to - bracket (no surface is invented across unobserved space).
//
// Stages (fusion/raycast_stages.h, InfiniTAM's split): range image, ray cast, pixel write; fusion/raycast_sampled.h
// runs them on a mask's pixels only. The sampler they share: fusion/volume_sampler.h.
//
// Thread-safety: raycast() reads the grid only and runs in parallel over 16 x 16 pixel tiles (TBB); the grid must
// not be modified (integrate, allocate, release) while it runs. Deterministic: the result does not depend on the
// thread count.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/camera.h"
#include "core/device_copy.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/voxel_block_grid.h"
#include "fusion/volume_sampler.h"

namespace hf::fusion {

struct RaycastOptions {
  double min_depth_m = 0.2;      // rays start here (depth along the optical axis) ...
  double max_depth_m = 8.0;      // ... and give up here
  double step_fraction = 0.8;    // fine step = step_fraction * |sdf| * mu; < 1 so no crossing is jumped over
  double min_step_vox = 0.5;     // lower bound of the fine step, in voxels
  float min_weight = 0.0f;       // voxels with a smaller weight count as unobserved (weight 0 always does)
  // The crossing's bracket is refined (Illinois regula falsi, at most 6 samples) until it is narrower than this,
  // in voxels. 0.001 makes the hinted and the full march return the same crossing (tests/fusion/test_raycast.cpp);
  // a tracking raycast needs far less than the sensor's millimetres (slam/pipeline.h uses 0.05).
  double refine_tol_vox = 1e-3;
  bool shade = true;             // fill RaycastResult::shaded
  // Fill RaycastResult::color (a trilinear colour sample per hit). Frame-to-model tracking does not read the
  // model's colour (photometric rows align frame to frame, registration/photometric.h), so the SLAM pipeline's
  // tracking raycast turns it off; the colour image is then black.
  bool color = true;
  // Skip whole blocks with no surface inside (VoxelBlockGrid::surface_free, kept by integrate()) in one step
  // instead of crossing them voxel by voxel. Turning it off changes the cost, and the result only where two
  // sampling patterns of the same field differ anyway: at silhouettes and the fringe of the observed volume
  // (tests/fusion/test_raycast.cpp). It is here for that comparison.
  bool skip_blocks = true;
  // The depth image just integrated from this same pose (same size as the camera; metres along the optical axis,
  // 0 = none), or nullptr. Not owned; must outlive the raycast() call. A ray whose pixel has a hint d > 0 searches
  // the bracket [d - w, d + w], w = mu + 2 voxels + 3 sigma_z(d) (hf_raycast_hint_halfwidth in
  // fusion/kernels/raycast_kernels.h: sigma_z is the Kinect's axial noise at d), outwards from d: one trilinear
  // sample at d; in front of the surface (sdf >= 0) the march goes on forward to d + w, behind it (sdf < 0) the
  // ray walks back towards the camera with the same SDF-bounded steps until the SDF turns positive. When that finds
  // no + to - crossing (or the walk back meets an unobserved sample), or the pixel has no hint (0, negative or not
  // finite), the ray marches from min_depth_m as without a hint. Most rays then take three or four samples instead
  // of crossing the free space in front of the surface.
  //   The semantic difference: without a hint the result is the FIRST + to - crossing along the ray; with one, it
  // is the crossing nearest to d on the side the sample at d says (so a surface in front of it within the bracket
  // is skipped too). At the pose the hint was integrated from, the space in front of d is what the frame has just
  // measured through (carved as free), so only stale model surface there, a sliver at a silhouette (where
  // trilinear interpolation spans both sides of a depth edge) or a second crossing of a noisy far surface is
  // skipped. Where both find the same crossing they agree to within 0.01 voxel in depth and 0.5 degrees in normal
  // (the crossing is refined to 0.001 voxel); measured on fused sphere and noisy room scenes, 0.1-0.5 % of the
  // pixels differ, at silhouettes and on noisy far or grazing surfaces (tests/fusion/test_raycast.cpp).
  const DepthImage* depth_hint = nullptr;
  // Throws hf::Error naming the bad field: 0 < min_depth_m < max_depth_m (finite), step_fraction in (0, 1),
  // min_step_vox in (0, 4], min_weight >= 0, refine_tol_vox in (0, 1].
  void validate() const;
  // The same, plus: a depth_hint must have the camera's size.
  void validate(const PinholeCamera& camera) const;
};

struct RaycastResult {
  DepthImage depth;      // metres along the optical axis, 0 = no surface
  VertexMap vertices;    // camera frame, w = 1 at hits
  NormalMap normals;     // camera frame, unit, pointing into free space (towards the camera for front faces)
  ColorImage color;      // the model's colour, black where no hit
  ColorImage shaded;     // grey head-light shading of the normals, for people (empty unless options.shade)
  int hit_count = 0;     // pixels with a surface
  // Device copies of depth / vertices / normals (core/device_copy.h): DeviceVoxelGrid::raycast publishes its
  // buffers; raycast() on the host, writing the images in place, drops them.
  DeviceCopies device_copies;
};

// How far from a point of a ray raycast() reads voxels, in voxels: a trilinear sample's corners and the 4 x 4 x 4
// neighbourhood of its normal lie within 2 voxels per axis of the sample (2 sqrt(3) = 3.46 voxels).
constexpr double kRaycastReachVox = 3.5;

// The blocks a raycast() from T_world_camera with these options may read, in the grid's hash order: every block
// whose bounding sphere comes within kRaycastReachVox voxels of the view frustum between min_depth_m and
// max_depth_m (its sides one pixel outside the image). raycast() builds its range image from these only, so per
// frame it costs one sphere test per block of the map and otherwise scales with the view, not the map. With
// surface_free, also their VoxelBlockGrid::surface_free flags (same order).
std::vector<std::pair<BlockCoord, const VoxelBlock*>> blocks_in_view(const VoxelBlockGrid& grid,
                                                                     const PinholeCamera& camera,
                                                                     const SE3& T_world_camera,
                                                                     const RaycastOptions& options,
                                                                     std::vector<std::uint8_t>* surface_free = nullptr);

// InfiniTAM's forward projection of the last raycast: the depth a camera at the current pose sees of the vertices
// of a vertex map taken at another pose (w = 1 valid, that camera's frame), T_cur_prev taking those to the current
// camera frame. Each vertex lands on the pixel nearest to its projection; per pixel the nearest (smallest z > 0)
// is kept, 0 where none lands. A SLAM pipeline fills the holes of RaycastOptions::depth_hint with it: where the
// frame has no depth, the model's surface seen from the last pose tells the ray where to look. *out gets the
// camera's size. Throws hf::Error when T_cur_prev is not finite.
void forward_project_depth(const VertexMap& vertices, const SE3& T_cur_prev, const PinholeCamera& camera,
                           DepthImage* out);

// Throws hf::Error for invalid options or a camera with non-positive size or focal length.
RaycastResult raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                      const RaycastOptions& options = {});
// Same, reusing the images in *out (no allocation when the size is unchanged).
void raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
             const RaycastOptions& options, RaycastResult* out);

// The render for people in the map's colours: per pixel the head-light shading modulated by the fused colour,
// colour x shade / 255 per channel, so a surface facing the camera shows its fused colour and one at a grazing angle
// darkens towards 0.2 of it (hf_headlight_shade's ambient). A hit whose colour is black keeps the grey shading: no
// colour was fused there (a map integrated without colour images, carving-only voxels, options.color off). Misses
// stay black. The viewer's GL mesh shader with vertex colours evaluates the same formula (viewer/mesh_renderer.h).
// Needs a result raycast with options.shade (throws hf::Error on an empty `shaded`).
ColorImage colored_shading(const RaycastResult& result);

}  // namespace hf::fusion
