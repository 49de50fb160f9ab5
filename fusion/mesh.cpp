#include "fusion/mesh.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <string>
#include <unordered_map>

#include "core/error.h"
#include "fusion/kernels/marching_cubes_tables.h"
#include "fusion/raycast.h"

namespace hf::fusion {

void MeshOptions::validate() const {
  if (!(std::isfinite(min_weight) && min_weight >= 0.0f))
    throw Error("invalid mesh options: min_weight must be finite and >= 0, got " + std::to_string(min_weight));
}

namespace {

constexpr int kEdgeBits = HF_VOXELS_PER_BLOCK * 3;  // one bit per (voxel, axis) edge a block owns
constexpr int kEdgeWords = kEdgeBits / 64;

// A grid edge: from voxel (i, j, k) to its +axis neighbour. It is owned by the block of voxel (i, j, k).
struct EdgeRef {
  int i, j, k, axis;
};

struct BlockMesh {
  std::array<std::uint64_t, kEdgeWords> crossed{};  // bit 3 * voxel_index + axis
  std::array<std::uint32_t, kEdgeWords> rank{};     // vertices owned before word w
  std::vector<Eigen::Vector3f> positions;
  std::vector<Eigen::Vector3f> normals;
  std::vector<std::uint8_t> normal_ok;
  std::vector<Rgb8> colors;
  std::vector<std::array<EdgeRef, 3>> triangles;
  size_t cells = 0;
};

Rgb8 lerp_color(const Voxel& a, const Voxel& b, float t) {
  auto ch = [t](std::uint8_t x, std::uint8_t y) {
    return std::uint8_t(std::clamp(float(x) + (float(y) - float(x)) * t + 0.5f, 0.0f, 255.0f));
  };
  return Rgb8{ch(a.r, b.r), ch(a.g, b.g), ch(a.b, b.b)};
}

void mesh_block(const BlockCoord& bc, const BlockLookup& lookup, std::uint16_t min_weight_raw, float min_weight,
                const MeshOptions& options, double voxel_m, BlockMesh* out) {
  // The block and its seven +x/+y/+z neighbours; local coordinates 0..8 reach into them.
  const VoxelBlock* nb[8];
  for (int n = 0; n < 8; ++n) nb[n] = lookup.find(bc.x + (n & 1), bc.y + ((n >> 1) & 1), bc.z + (n >> 2));
  auto at = [&](int x, int y, int z) -> const Voxel* {
    const VoxelBlock* b = nb[(x >> 3) + 2 * (y >> 3) + 4 * (z >> 3)];
    return b ? &b->voxels[hf_voxel_index(x & 7, y & 7, z & 7)] : nullptr;
  };
  auto observed = [min_weight_raw](const Voxel* v) {
    return v != nullptr && v->weight != 0 && v->weight >= min_weight_raw;
  };
  const int gx = bc.x * HF_BLOCK_SIZE, gy = bc.y * HF_BLOCK_SIZE, gz = bc.z * HF_BLOCK_SIZE;
  VolumeSampler sampler(lookup, min_weight);

  // Vertices on the edges this block owns, in bit order.
  for (int z = 0; z < HF_BLOCK_SIZE; ++z)
    for (int y = 0; y < HF_BLOCK_SIZE; ++y)
      for (int x = 0; x < HF_BLOCK_SIZE; ++x) {
        const Voxel* v = at(x, y, z);
        if (!observed(v)) continue;
        const int vi = hf_voxel_index(x, y, z);
        for (int a = 0; a < 3; ++a) {
          const Voxel* w = at(x + (a == 0), y + (a == 1), z + (a == 2));
          if (!observed(w) || (v->sdf < 0) == (w->sdf < 0)) continue;
          const int bit = 3 * vi + a;
          out->crossed[bit >> 6] |= std::uint64_t(1) << (bit & 63);
          // A stored zero counts as outside (sign test above); half a quantisation step outside keeps the vertex
          // off the voxel itself, where up to six edges would otherwise put coincident vertices.
          const float half_step = 0.5f / HF_SDF_SCALE;
          const float sv = v->sdf == 0 ? half_step : hf_voxel_sdf(*v), sw = w->sdf == 0 ? half_step : hf_voxel_sdf(*w);
          const float t = sv / (sv - sw);
          Eigen::Vector3f p_vox(float(gx + x), float(gy + y), float(gz + z));
          p_vox[a] += t;
          out->positions.push_back(((p_vox.array() + 0.5f) * float(voxel_m)).matrix());
          if (options.colors) out->colors.push_back(lerp_color(*v, *w, t));
          if (options.normals) {
            Eigen::Vector3f n(0.0f, 0.0f, 0.0f);
            const bool ok = sampler.normal(p_vox, &n);
            out->normals.push_back(n);
            out->normal_ok.push_back(ok ? 1 : 0);
          }
        }
      }
  std::uint32_t r = 0;
  for (int w = 0; w < kEdgeWords; ++w) {
    out->rank[w] = r;
    r += std::uint32_t(std::popcount(out->crossed[w]));
  }

  // Triangles of the cells whose lower corner lies in this block.
  for (int z = 0; z < HF_BLOCK_SIZE; ++z)
    for (int y = 0; y < HF_BLOCK_SIZE; ++y)
      for (int x = 0; x < HF_BLOCK_SIZE; ++x) {
        int cube = 0;
        bool ok = true;
        for (int c = 0; c < 8 && ok; ++c) {
          const Voxel* v = at(x + hf_mc_corner_offset[c][0], y + hf_mc_corner_offset[c][1], z + hf_mc_corner_offset[c][2]);
          ok = observed(v);
          if (ok && v->sdf < 0) cube |= 1 << c;
        }
        if (!ok || hf_mc_edge_table[cube] == 0) continue;
        ++out->cells;
        for (int t = 0; t < HF_MC_MAX_TRIANGLES && hf_mc_triangle_table[cube][3 * t] >= 0; ++t) {
          std::array<EdgeRef, 3> tri;
          for (int k = 0; k < 3; ++k) {
            const int e = hf_mc_triangle_table[cube][3 * t + k];
            const int c = hf_mc_edge_axis[e][0];
            tri[k] = EdgeRef{gx + x + hf_mc_corner_offset[c][0], gy + y + hf_mc_corner_offset[c][1],
                             gz + z + hf_mc_corner_offset[c][2], hf_mc_edge_axis[e][1]};
          }
          out->triangles.push_back(tri);
        }
      }
}

TriangleMesh mesh_blocks(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks, double voxel_m,
                         const MeshOptions& options, MeshStats* stats) {
  options.validate();
  const BlockLookup lookup(blocks);
  // Block coordinate -> index of its result; a repeated coordinate is meshed once (its first entry).
  std::unordered_map<BlockCoord, std::uint32_t, BlockCoordHash> index;
  index.reserve(blocks.size());
  std::vector<std::uint8_t> skip(blocks.size(), 0);
  for (size_t b = 0; b < blocks.size(); ++b)
    if (!index.emplace(blocks[b].first, std::uint32_t(b)).second) skip[b] = 1;

  const std::uint16_t min_weight_raw = hf_quantise_weight(options.min_weight);
  std::vector<BlockMesh> results(blocks.size());
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
    if (!skip[b]) mesh_block(blocks[b].first, lookup, min_weight_raw, options.min_weight, options, voxel_m, &results[b]);
  });

  // Global vertex numbering: blocks in order, each block's vertices in bit order.
  std::vector<size_t> vertex_offset(blocks.size() + 1, 0), triangle_offset(blocks.size() + 1, 0);
  for (size_t b = 0; b < blocks.size(); ++b) {
    vertex_offset[b + 1] = vertex_offset[b] + results[b].positions.size();
    triangle_offset[b + 1] = triangle_offset[b] + results[b].triangles.size();
  }
  const size_t n_vertices = vertex_offset.back();
  if (n_vertices > size_t(2147483647)) throw Error("extract_mesh: more than 2^31 vertices; mesh a smaller region");
  std::vector<Eigen::Vector3i> triangles(triangle_offset.back());
  tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
    for (size_t t = 0; t < results[b].triangles.size(); ++t) {
      Eigen::Vector3i tri;
      for (int k = 0; k < 3; ++k) {
        const EdgeRef& e = results[b].triangles[t][k];
        const auto it = index.find(BlockCoord{e.i >> 3, e.j >> 3, e.k >> 3});
        const int bit = 3 * hf_voxel_index(e.i & 7, e.j & 7, e.k & 7) + e.axis;
        // Both ends of a crossed edge of a meshed cell are observed, so the owner block exists and made the
        // vertex with the same sign test; anything else is a bug.
        if (it == index.end() || !((results[it->second].crossed[bit >> 6] >> (bit & 63)) & 1))
          throw Error("extract_mesh: internal error: a cell edge has no vertex");
        const BlockMesh& owner = results[it->second];
        const std::uint64_t below = owner.crossed[bit >> 6] & ((std::uint64_t(1) << (bit & 63)) - 1);
        tri[k] = int(vertex_offset[it->second] + owner.rank[bit >> 6] + std::uint32_t(std::popcount(below)));
      }
      triangles[triangle_offset[b] + t] = tri;
    }
  });

  // Keep only vertices some triangle uses (an edge can cross with none of its four cells fully observed).
  std::vector<std::int32_t> remap(n_vertices, -1);
  for (const auto& tri : triangles)
    for (int k = 0; k < 3; ++k) remap[size_t(tri[k])] = 0;
  TriangleMesh mesh;
  std::vector<std::uint8_t> normal_ok;
  std::int32_t next = 0;
  for (size_t b = 0; b < blocks.size(); ++b) {
    const BlockMesh& r = results[b];
    for (size_t v = 0; v < r.positions.size(); ++v) {
      std::int32_t& m = remap[vertex_offset[b] + v];
      if (m < 0) continue;
      m = next++;
      mesh.vertices.push_back(r.positions[v]);
      if (options.colors) mesh.colors.push_back(r.colors[v]);
      if (options.normals) {
        mesh.normals.push_back(r.normals[v]);
        normal_ok.push_back(r.normal_ok[v]);
      }
    }
  }
  for (auto& tri : triangles)
    for (int k = 0; k < 3; ++k) tri[k] = remap[size_t(tri[k])];
  mesh.triangles = std::move(triangles);

  if (options.normals) {
    // Where the gradient could not be taken: the area-weighted normal of the vertex's triangles.
    std::vector<Eigen::Vector3f> acc;
    bool any = std::find(normal_ok.begin(), normal_ok.end(), 0) != normal_ok.end();
    if (any) {
      acc.assign(mesh.vertices.size(), Eigen::Vector3f::Zero());
      for (const auto& tri : mesh.triangles) {
        const Eigen::Vector3f n = (mesh.vertices[tri[1]] - mesh.vertices[tri[0]])
                                      .cross(mesh.vertices[tri[2]] - mesh.vertices[tri[0]]);
        for (int k = 0; k < 3; ++k)
          if (!normal_ok[size_t(tri[k])]) acc[size_t(tri[k])] += n;
      }
      for (size_t v = 0; v < mesh.vertices.size(); ++v) {
        if (normal_ok[v]) continue;
        const float len = acc[v].norm();
        mesh.normals[v] = len > 0.0f ? Eigen::Vector3f(acc[v] / len) : Eigen::Vector3f(0.0f, 0.0f, 1.0f);
      }
    }
  }

  if (stats) {
    stats->blocks = index.size();
    stats->cells_meshed = 0;
    for (const auto& r : results) stats->cells_meshed += r.cells;
  }
  return mesh;
}

}  // namespace

TriangleMesh extract_mesh(const VoxelBlockGrid& grid, const MeshOptions& options, MeshStats* stats) {
  return mesh_blocks(grid.blocks(), grid.params().voxel_m, options, stats);
}

TriangleMesh extract_mesh(const VoxelBlockGrid& grid, const BlockStore& store, const MeshOptions& options,
                          MeshStats* stats) {
  std::vector<std::pair<BlockCoord, const VoxelBlock*>> blocks;
  blocks.reserve(grid.block_count() + store.size());
  for_each_block_including_streamed(grid, store, [&](const BlockCoord& c, const VoxelBlock& b) {
    blocks.emplace_back(c, &b);
  });
  std::stable_sort(blocks.begin(), blocks.end(), [](const auto& a, const auto& b) { return block_coord_less(a.first, b.first); });
  return mesh_blocks(blocks, grid.params().voxel_m, options, stats);
}

TriangleMesh extract_mesh(const std::vector<std::pair<BlockCoord, const VoxelBlock*>>& blocks,
                          const VolumeParams& params, const MeshOptions& options, MeshStats* stats) {
  params.validate();
  return mesh_blocks(blocks, params.voxel_m, options, stats);
}

}  // namespace hf::fusion
