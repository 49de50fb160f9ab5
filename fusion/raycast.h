// Raycasting the TSDF: the model image that frame-to-model tracking aligns against, and a shaded render for people.
//
//   RaycastResult r = raycast(grid, camera, T_world_camera);   // vertex/normal/colour/depth maps, camera frame
//
// Per pixel (KinectFusion / InfiniTAM / Niessner et al. 2013): the ray from the camera centre through the pixel
// centre is marched from min_depth_m to max_depth_m. Where the block containing the ray point does not exist the
// ray jumps to where it leaves that block (free space and unseen space are never stepped through voxel by voxel);
// inside allocated blocks it takes steps of step_fraction * sdf * mu (at least min_step_vox voxels), sampling the
// trilinearly interpolated SDF. The first sign change from + to - is the surface (a change from - to +, seen when a
// ray leaves the back of a surface, is ignored); the crossing is refined by linear interpolation of the two
// bracketing samples (then two regula-falsi steps on the same bracket). Normals are the normalised SDF gradient
// by central differences of trilinear samples one voxel apart; colour is trilinear.
//
// Outputs are in the CAMERA frame (x right, y down, z forward, metres); depth is z along the optical axis, like a
// depth image. Pixels without a hit have depth 0, vertex/normal w = 0, colour black. A hit whose gradient cannot
// be taken (a neighbouring sample unobserved) keeps its vertex and gets an invalid normal.
//
// A sample is valid only when its eight voxels are observed (weight > 0 and >= min_weight); invalid samples are
// stepped over one voxel at a time and break a + to - bracket (no surface is invented across unobserved space).
//
// Thread-safety: raycast() reads the grid only and runs in parallel over rows (core/parallel.h); the grid must
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
#include "fusion/voxel_block_grid.h"

namespace hf::fusion {

// A read-only snapshot of block pointers with lock-free lookups (open addressing), for passes that look blocks up
// millions of times (raycasting, meshing) where the grid's own find() would take its lock each time. Valid while
// the blocks it was built from are neither released nor moved.
class BlockLookup {
 public:
  BlockLookup() = default;
  explicit BlockLookup(const VoxelBlockGrid& grid);
  explicit BlockLookup(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks);

  const VoxelBlock* find(int bx, int by, int bz) const {
    if (slots_.empty()) return nullptr;
    size_t i = BlockCoordHash{}(BlockCoord{bx, by, bz}) & mask_;
    for (;;) {
      const Slot& s = slots_[i];
      if (s.block == nullptr) return nullptr;
      if (s.x == bx && s.y == by && s.z == bz) return s.block;
      i = (i + 1) & mask_;
    }
  }
  size_t size() const { return size_; }

 private:
  struct Slot {
    int x = 0, y = 0, z = 0;
    const VoxelBlock* block = nullptr;
  };
  std::vector<Slot> slots_;
  size_t mask_ = 0;
  size_t size_ = 0;
};

// Voxel access and trilinear sampling in continuous voxel coordinates (voxel centres at integers, see
// VoxelBlockGrid::voxel_coords). Caches the last block, so neighbouring samples cost no hash lookup. One sampler per
// thread (not thread-safe itself); many samplers may share one BlockLookup.
class VolumeSampler {
 public:
  // Voxels with weight < min_weight count as unobserved, as do never-observed voxels (weight 0) always.
  VolumeSampler(const BlockLookup& lookup, float min_weight);

  // The voxel at world-grid index (i, j, k), or nullptr when its block does not exist.
  const Voxel* voxel(int i, int j, int k) {
    const int bx = i >> 3, by = j >> 3, bz = k >> 3;  // arithmetic shift: floor division by 8
    if (bx != cx_ || by != cy_ || bz != cz_) {
      cached_ = lookup_->find(bx, by, bz);
      cx_ = bx, cy_ = by, cz_ = bz;
    }
    return cached_ ? &cached_->voxels[hf_voxel_index(i & 7, j & 7, k & 7)] : nullptr;
  }
  bool observed(const Voxel* v) const { return v != nullptr && v->weight != 0 && v->weight >= min_weight_raw_; }

  // Trilinear normalised SDF at p_vox; false when any of the eight voxels is unobserved.
  bool sdf(const Eigen::Vector3f& p_vox, float* sdf);
  // The same plus trilinear colour (0..255 per channel).
  bool sdf_color(const Eigen::Vector3f& p_vox, float* sdf, Eigen::Vector3f* rgb);
  // Unit SDF gradient (pointing into free space) by central differences of trilinear samples h_vox apart; false
  // when a sample is unobserved or the gradient vanishes.
  bool normal(const Eigen::Vector3f& p_vox, Eigen::Vector3f* n, float h_vox = 1.0f);

 private:
  bool corners(const Eigen::Vector3f& p_vox, const Voxel* v[8], float f[3]);

  const BlockLookup* lookup_;
  std::uint16_t min_weight_raw_;
  int cx_ = -2147483647 - 1, cy_ = 0, cz_ = 0;  // no block cached yet (block x never reaches INT_MIN)
  const VoxelBlock* cached_ = nullptr;
};

struct RaycastOptions {
  double min_depth_m = 0.2;      // rays start here (depth along the optical axis) ...
  double max_depth_m = 8.0;      // ... and give up here
  double step_fraction = 0.8;    // fine step = step_fraction * |sdf| * mu; < 1 so no crossing is jumped over
  double min_step_vox = 0.5;     // lower bound of the fine step, in voxels
  float min_weight = 0.0f;       // voxels with a smaller weight count as unobserved (weight 0 always does)
  bool shade = true;             // fill RaycastResult::shaded
  // Throws hf::Error naming the bad field: 0 < min_depth_m < max_depth_m (finite), step_fraction in (0, 1),
  // min_step_vox in (0, 4], min_weight >= 0.
  void validate() const;
};

struct RaycastResult {
  DepthImage depth;      // metres along the optical axis, 0 = no surface
  VertexMap vertices;    // camera frame, w = 1 at hits
  NormalMap normals;     // camera frame, unit, pointing into free space (towards the camera for front faces)
  ColorImage color;      // the model's colour, black where no hit
  ColorImage shaded;     // grey head-light shading of the normals, for people (empty unless options.shade)
  int hit_count = 0;     // pixels with a surface
};

// Throws hf::Error for invalid options or a camera with non-positive size or focal length.
RaycastResult raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
                      const RaycastOptions& options = {});
// Same, reusing the images in *out (no allocation when the size is unchanged).
void raycast(const VoxelBlockGrid& grid, const PinholeCamera& camera, const SE3& T_world_camera,
             const RaycastOptions& options, RaycastResult* out);

}  // namespace hf::fusion
