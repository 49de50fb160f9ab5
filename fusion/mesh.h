// Marching-cubes meshing of the TSDF (Lorensen & Cline 1987) over the allocated voxel blocks.
//
//   TriangleMesh mesh = extract_mesh(grid);          // world frame, metres
//   write_ply("map.ply", mesh);                       // io/ply.h: binary PLY, written atomically
//
// Cells: the cell with lower corner voxel (i, j, k) spans the voxel centres (i..i+1, j..j+1, k..k+1); it belongs to
// the block of voxel (i, j, k), and its corners in the neighbouring blocks (+x, +y, +z and the diagonals) are
// looked up there, so the surface continues across block borders without seams. A cell is meshed only when all
// eight corners are observed (weight > 0 and >= min_weight, the minimum-weight filter): no surface is invented
// next to unobserved space.
//
// Vertices are welded: one vertex per grid edge whose two voxels have opposite signs (sdf < 0 inside), shared by
// the up to four cells around that edge, at the linear zero crossing along the edge. Per-vertex colour is
// interpolated along the edge; the normal is the SDF gradient (central differences of trilinear samples one voxel
// apart), falling back to the area-weighted normal of the vertex's triangles where a sample is unobserved.
// Triangles are wound counter-clockwise seen from free space (fusion/kernels/marching_cubes_tables.h), so their
// normals agree with the vertex normals. A closed observed surface gives a closed (watertight) mesh.
//
// Output order is deterministic (blocks in block_coords() order, then voxels and edges in index order), and does
// not depend on the thread count. Parallel over blocks (TBB).
//
// Thread-safety: reads the grid only; the grid must not be modified while this runs.
#pragma once

#include <utility>
#include <vector>

#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"
#include "io/mesh.h"

namespace hf::fusion {

struct MeshOptions {
  float min_weight = 0.0f;  // voxels with a smaller weight count as unobserved (weight 0 always does)
  bool colors = true;       // per-vertex colour
  bool normals = true;      // per-vertex normal
  void validate() const;    // throws hf::Error: min_weight must be finite and >= 0
};

struct MeshStats {
  size_t blocks = 0;         // blocks visited
  size_t cells_meshed = 0;   // cells with all corners observed that produced triangles
};

// The mesh of every block in the grid.
TriangleMesh extract_mesh(const VoxelBlockGrid& grid, const MeshOptions& options = {}, MeshStats* stats = nullptr);

// The whole map: the grid's blocks and those streamed out to `store` (fusion/streaming.h), without bringing any
// back into the pool. Blocks are meshed in (z, y, x) order wherever they live, so streaming blocks out and back
// in leaves the mesh identical.
TriangleMesh extract_mesh(const VoxelBlockGrid& grid, const BlockStore& store, const MeshOptions& options = {},
                          MeshStats* stats = nullptr);

// The mesh of an explicit set of blocks (e.g. the grid's blocks plus blocks streamed out to a host store), all at
// the geometry of `params` (voxel_m). Neighbour lookups across block borders use the same set. The blocks are
// meshed in the given order (pass them sorted by (z, y, x) for the same output as the grid overload). A
// coordinate given twice: the first block is used.
TriangleMesh extract_mesh(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks,
                          const VolumeParams& params, const MeshOptions& options = {}, MeshStats* stats = nullptr);

}  // namespace hf::fusion
