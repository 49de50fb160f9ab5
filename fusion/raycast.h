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
// Thread-safety: raycast() reads the grid only and runs in parallel over 16 x 16 pixel tiles (TBB); the grid must
// not be modified (integrate, allocate, release) while it runs. Deterministic: the result does not depend on the
// thread count.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <utility>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/block_hash_table.h"
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

// A look-up table over a list of blocks that is not a grid (meshing a given set of blocks, e.g. one read back
// from a stream): the same hash table as VoxelBlockGrid (fusion/block_hash_table.h) and the same questions
// (find, region_occupied). Valid while the blocks it was built from are neither released nor moved. A grid needs
// none of this: VoxelBlockGrid::find is lock-free, and a VolumeSampler reads it directly.
class BlockLookup {
 public:
  BlockLookup() = default;
  // surface_free: one flag per block (same order), or nullptr (no block is skippable). A coordinate listed twice
  // keeps its first block.
  explicit BlockLookup(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks,
                       const std::vector<std::uint8_t>* surface_free = nullptr);

  const VoxelBlock* find(int bx, int by, int bz) const {
    const std::uint32_t v = table_.find(bx, by, bz);
    return v != 0 ? blocks_[v - 1] : nullptr;
  }
  // Also whether a raycast may skip the block (its surface_free flag; false for a missing block).
  const VoxelBlock* find(int bx, int by, int bz, bool* skippable) const {
    const std::uint32_t v = table_.find(bx, by, bz);
    *skippable = v != 0 && skippable_[v - 1] != 0;
    return v != 0 ? blocks_[v - 1] : nullptr;
  }
  size_t size() const { return table_.size(); }
  // VoxelBlockGrid::region_occupied for the listed blocks.
  bool region_occupied(int rx, int ry, int rz) const { return regions_.find(rx, ry, rz) != 0; }

 private:
  BlockHashTable table_;    // coordinate -> index into blocks_ + 1
  BlockHashTable regions_;  // region -> 1
  std::vector<const VoxelBlock*> blocks_;
  std::vector<std::uint8_t> skippable_;
};

// Voxel access and trilinear sampling in continuous voxel coordinates (voxel centres at integers, see
// VoxelBlockGrid::voxel_coords). Caches the last blocks, so neighbouring samples cost no hash lookup, and the last
// trilinear cell's eight values, so samples in the same cell (a march's short steps near the surface, the
// refinement of a crossing) cost no gather. One sampler per thread (not thread-safe itself); many samplers may
// share one grid or BlockLookup. The caches only save work: every result equals the uncached computation bit for bit.
class VolumeSampler {
 public:
  // Voxels with weight < min_weight count as unobserved, as do never-observed voxels (weight 0) always. On a
  // grid, skippable blocks are its surface_free() ones when skip_surface_free (else none); the grid must not be
  // changed while the sampler reads it except by allocate().
  VolumeSampler(const VoxelBlockGrid& grid, float min_weight, bool skip_surface_free = true);
  VolumeSampler(const BlockLookup& lookup, float min_weight);

  // The voxel at world-grid index (i, j, k), or nullptr when its block does not exist.
  const Voxel* voxel(int i, int j, int k) {
    const VoxelBlock* b = block(i >> 3, j >> 3, k >> 3);  // arithmetic shift: floor division by 8
    return b ? &b->voxels[hf_voxel_index(i & 7, j & 7, k & 7)] : nullptr;
  }
  // The block at block coordinates (bx, by, bz) or nullptr. Cached in 8 entries chosen by the parity of the
  // coordinates, so the up to 8 blocks of any 2 x 2 x 2 neighbourhood (a trilinear sample or a gradient across a
  // block border) stay cached together.
  const VoxelBlock* block(int bx, int by, int bz) {
    bool unused;
    return block(bx, by, bz, &unused);
  }
  // The same, and whether a raycast may skip it (BlockLookup::find).
  const VoxelBlock* block(int bx, int by, int bz, bool* skippable) {
    CacheEntry& e = cache_[(bx & 1) | ((by & 1) << 1) | ((bz & 1) << 2)];
    if (bx != e.x || by != e.y || bz != e.z) {
      if (grid_ != nullptr) {
        e.block = grid_->find(BlockCoord{bx, by, bz}, &e.skippable);
        e.skippable = e.skippable && skip_surface_free_;
      } else {
        e.block = lookup_->find(bx, by, bz, &e.skippable);
      }
      e.x = bx, e.y = by, e.z = bz;
    }
    *skippable = e.skippable;
    return e.block;
  }
  // VoxelBlockGrid::region_occupied with the last region cached.
  bool region_occupied(int rx, int ry, int rz) {
    if (rx != rx_ || ry != ry_ || rz != rz_) {
      region_ = grid_ != nullptr ? grid_->region_occupied(rx, ry, rz) : lookup_->region_occupied(rx, ry, rz);
      rx_ = rx, ry_ = ry, rz_ = rz;
    }
    return region_;
  }
  bool observed(const Voxel* v) const { return v != nullptr && v->weight >= min_weight_raw_; }

  // Trilinear normalised SDF at p_vox; false when any of the eight voxels is unobserved.
  bool sdf(const Eigen::Vector3f& p_vox, float* sdf);
  // The same plus trilinear colour (0..255 per channel).
  bool sdf_color(const Eigen::Vector3f& p_vox, float* sdf, Eigen::Vector3f* rgb);
  // Unit SDF gradient (pointing into free space) by central differences of trilinear samples h_vox apart; false
  // when a sample is unobserved or the gradient vanishes. For h_vox = 1 the six samples share their fractional
  // offset, so their 48 corners are 32 voxels of the 4 x 4 x 4 neighbourhood of p_vox: those are gathered once
  // (the at most 8 blocks it touches looked up once, no per-voxel branch) instead of six separate trilinear
  // look-ups.
  bool normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox = 1.0f);

  // The general paths the fast ones above replace, kept as their reference (tests/fusion/test_raycast.cpp holds
  // sdf, sdf_color and normal to them bit for bit): every voxel through voxel(), no cell cache, early exits.
  bool sdf_reference(const Eigen::Vector3f& p_vox, float* sdf);
  bool normal_reference(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n);

 private:
  // A missing block reads as this one: all voxels unobserved (weight 0), so gathers need no null checks.
  const VoxelBlock* block_or_empty(int bx, int by, int bz);
  // The 2 x 2 x 2 blocks from (bx, by, bz) (index x + 2 y + 4 z), each distinct one looked up once: cx, cy, cz
  // say whether the neighbourhood reaches the next block along x, y, z (else the entries repeat the lower ones).
  void neighbour_blocks(int bx, int by, int bz, bool cx, bool cy, bool cz, const VoxelBlock* B[8]);
  // The eight corner voxels of cell (i, j, k) (corner c = x + 2 y + 4 z), never nullptr.
  void gather_cell(int i, int j, int k, const Voxel* v[8]);
  // The raw (int16 as float) SDF of cell (i, j, k)'s corners, or nullptr when one is unobserved; cached.
  const float* cell(int i, int j, int k);
  bool corners_reference(const Eigen::Vector3f& p_vox, const Voxel* v[8], float f[3]);
  // Raw (int16 as float) SDF of voxels (i .. i + N - 1, j, k) into out; false when one is unobserved.
  template <int N>
  bool row(int i, int j, int k, float* out);

  const VoxelBlockGrid* grid_ = nullptr;  // one of these two
  const BlockLookup* lookup_ = nullptr;
  bool skip_surface_free_ = false;
  std::uint16_t min_weight_raw_;  // >= 1: weight 0 (never observed) is always unobserved
  struct CacheEntry {
    int x = -2147483647 - 1, y = 0, z = 0;  // nothing cached yet (block x never reaches INT_MIN)
    bool skippable = false;
    const VoxelBlock* block = nullptr;
  };
  CacheEntry cache_[8];
  int rx_ = -2147483647 - 1, ry_ = 0, rz_ = 0;
  bool region_ = false;
  int ci_ = -2147483647 - 1, cj_ = 0, ck_ = 0;  // the cached cell (none yet)
  bool cell_ok_ = false;
  float cell_[8] = {};
};

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

}  // namespace hf::fusion
