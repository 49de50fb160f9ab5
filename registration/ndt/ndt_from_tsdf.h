// The NDT cell model built directly from the voxel-hashed TSDF (fusion/voxel_block_grid.h), for frame-to-model
// NDT without a second point cloud: the surface samples are the TSDF's zero crossings along the voxel grid's
// edges (where an observed voxel and its +x, +y or +z neighbour, both with weight >= min_weight, differ in sign,
// the crossing is interpolated linearly between their centres: marching cubes' vertex positions; a sign change
// by more than two voxels of distance is a silhouette between free space and an occluded band, and skipped),
// accumulated
// into the cells like points. World frame, as the grid.
// Thread-safety: reads the grid only (no concurrent writes). Never throws; an empty grid gives empty levels.
#pragma once

#include <vector>

#include "fusion/voxel_block_grid.h"
#include "registration/ndt/ndt_cells.h"

namespace hf {

// The zero-crossing samples of every block (world frame, metres).
std::vector<Eigen::Vector3d> tsdf_surface_samples(const fusion::VoxelBlockGrid& grid, float min_weight = 0.0f);

NdtModel build_ndt_model_from_tsdf(const fusion::VoxelBlockGrid& grid, const std::vector<double>& resolutions_m,
                                   const NdtGridOptions& options = {}, float min_weight = 0.0f);

}  // namespace hf
