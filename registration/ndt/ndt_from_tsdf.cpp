#include "registration/ndt/ndt_from_tsdf.h"

#include <cmath>

namespace hf {

std::vector<Eigen::Vector3d> tsdf_surface_samples(const fusion::VoxelBlockGrid& grid, float min_weight) {
  std::vector<Eigen::Vector3d> samples;
  const double voxel_m = grid.params().voxel_m;
  // Between neighbouring centres a distance field changes by at most one voxel; a sign change by more than two is a
  // silhouette (free space beside an occluded band), not a surface (normalised units: sdf_m / mu).
  const float max_jump = float(2.0 / grid.params().truncation_vox);
  auto observed = [min_weight](const fusion::Voxel* v) {
    return v != nullptr && v->weight > 0 && hf_voxel_weight(*v) >= min_weight;
  };
  for (const auto& [c, block] : grid.blocks()) {
    for (int z = 0; z < HF_BLOCK_SIZE; ++z) {
      for (int y = 0; y < HF_BLOCK_SIZE; ++y) {
        for (int x = 0; x < HF_BLOCK_SIZE; ++x) {
          const fusion::Voxel& v = block->voxels[size_t(hf_voxel_index(x, y, z))];
          if (!observed(&v)) continue;
          const int i = c.x * HF_BLOCK_SIZE + x, j = c.y * HF_BLOCK_SIZE + y, k = c.z * HF_BLOCK_SIZE + z;
          const float a = hf_voxel_sdf(v);
          for (int axis = 0; axis < 3; ++axis) {
            const fusion::Voxel* n = grid.voxel(i + (axis == 0), j + (axis == 1), k + (axis == 2));
            if (!observed(n)) continue;
            const float b = hf_voxel_sdf(*n);
            if ((a > 0.0f) == (b > 0.0f) || a == b || std::abs(a - b) > max_jump) continue;
            const double t = double(a) / (double(a) - double(b));  // a + t (b - a) = 0
            Eigen::Vector3d p(i + 0.5, j + 0.5, k + 0.5);
            p(axis) += t;
            samples.push_back(p * voxel_m);
          }
        }
      }
    }
  }
  return samples;
}

NdtModel build_ndt_model_from_tsdf(const fusion::VoxelBlockGrid& grid, const std::vector<double>& resolutions_m,
                                   const NdtGridOptions& options, float min_weight) {
  return build_ndt_model(tsdf_surface_samples(grid, min_weight), resolutions_m, options);
}

}  // namespace hf
