// Marching cubes over analytic volumes: accuracy against the true surface, watertightness, welding, block borders,
// the minimum-weight filter, streamed-out blocks, and the tables themselves.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <map>
#include <random>
#include <set>
#include <tuple>

#include <Eigen/Geometry>

#include "fusion/kernels/marching_cubes_tables.h"
#include "fusion/mesh.h"
#include "fusion/streaming.h"
#include "io/ply.h"

namespace hf::fusion {
namespace {

using MeshSdfFn = std::function<double(const Eigen::Vector3d&)>;
using ColourFn = std::function<Rgb8(const Eigen::Vector3d&)>;

// Allocates every block within mu + a block diagonal of the surface and writes the truncated, normalised SDF.
void fill_mesh_sdf(VoxelBlockGrid& grid, const MeshSdfFn& sdf, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi,
          const ColourFn& colour = nullptr, float weight = 1.0f) {
  const double v = grid.params().voxel_m, mu = grid.params().truncation_m(), B = grid.params().block_m();
  const BlockCoord a = grid.block_of(lo), b = grid.block_of(hi);
  for (int bz = a.z; bz <= b.z; ++bz)
    for (int by = a.y; by <= b.y; ++by)
      for (int bx = a.x; bx <= b.x; ++bx) {
        const Eigen::Vector3d centre = (Eigen::Vector3d(bx, by, bz) + Eigen::Vector3d::Constant(0.5)) * B;
        if (std::abs(sdf(centre)) > mu + B) continue;
        VoxelBlock* block = grid.allocate({bx, by, bz});
        for (int z = 0; z < 8; ++z)
          for (int y = 0; y < 8; ++y)
            for (int x = 0; x < 8; ++x) {
              const Eigen::Vector3d p = (Eigen::Vector3d(8 * bx + x, 8 * by + y, 8 * bz + z) +
                                         Eigen::Vector3d::Constant(0.5)) * v;
              Voxel& vox = block->voxels[hf_voxel_index(x, y, z)];
              vox.sdf = hf_quantise_sdf(float(std::clamp(sdf(p) / mu, -1.0, 1.0)));
              vox.weight = hf_quantise_weight(weight);
              const Rgb8 c = colour ? colour(p) : Rgb8{200, 100, 50};
              vox.r = c.r, vox.g = c.g, vox.b = c.b;
            }
      }
}

VolumeParams mesh_params_1cm() {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.capacity_blocks = 1 << 14;
  return p;
}

// Every undirected edge is used by exactly two triangles, once in each direction (closed and consistently
// oriented); returns the number of undirected edges.
size_t check_closed_oriented(const TriangleMesh& mesh) {
  std::map<std::pair<int, int>, int> directed;
  for (const auto& t : mesh.triangles)
    for (int k = 0; k < 3; ++k) ++directed[{t[k], t[(k + 1) % 3]}];
  size_t undirected = 0;
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1) << "directed edge " << e.first << "->" << e.second << " used " << n << " times";
    const auto it = directed.find({e.second, e.first});
    EXPECT_TRUE(it != directed.end()) << "edge " << e.first << "-" << e.second << " is a border";
    if (e.first < e.second) ++undirected;
  }
  return undirected;
}

void check_welded(const TriangleMesh& mesh) {
  std::set<std::tuple<float, float, float>> seen;
  for (const auto& p : mesh.vertices) EXPECT_TRUE(seen.insert({p.x(), p.y(), p.z()}).second) << "duplicate vertex";
}

TEST(MarchingCubesTables, TrianglesUseExactlyTheCrossedEdges) {
  for (int cube = 0; cube < 256; ++cube) {
    int used = 0, count = 0;
    for (int i = 0; i < 3 * HF_MC_MAX_TRIANGLES && hf_mc_triangle_table[cube][i] >= 0; ++i, ++count)
      used |= 1 << hf_mc_triangle_table[cube][i];
    EXPECT_EQ(count % 3, 0) << cube;
    EXPECT_EQ(used, hf_mc_edge_table[cube]) << "case " << cube;
    for (int e = 0; e < 12; ++e) {
      const int a = hf_mc_edge_corners[e][0], b = hf_mc_edge_corners[e][1];
      EXPECT_EQ(((cube >> a) & 1) != ((cube >> b) & 1), ((hf_mc_edge_table[cube] >> e) & 1) != 0);
      // hf_mc_edge_axis names the same edge as the corner pair.
      const int lower = hf_mc_edge_axis[e][0], axis = hf_mc_edge_axis[e][1];
      int upper_offset[3] = {hf_mc_corner_offset[lower][0], hf_mc_corner_offset[lower][1], hf_mc_corner_offset[lower][2]};
      upper_offset[axis] += 1;
      const bool a_lower = a == lower, b_lower = b == lower;
      ASSERT_TRUE(a_lower || b_lower) << e;
      const int upper = a_lower ? b : a;
      for (int k = 0; k < 3; ++k) EXPECT_EQ(hf_mc_corner_offset[upper][k], upper_offset[k]) << e;
    }
  }
}

TEST(Mesh, SphereIsAccurateWatertightWeldedAndOutwardAcrossBlocks) {
  VoxelBlockGrid grid(mesh_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  const double r = 0.3;
  fill_mesh_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - r; }, c.array() - 0.45, c.array() + 0.45);
  ASSERT_GT(grid.block_count(), 100u);
  MeshStats stats;
  const TriangleMesh mesh = extract_mesh(grid, {}, &stats);
  ASSERT_NO_THROW(mesh.validate());
  ASSERT_GT(mesh.triangles.size(), 1000u);
  EXPECT_EQ(stats.blocks, grid.block_count());
  // Linear interpolation of the exact SDF along a 1 cm edge: error <= h^2 / (8 r) = 0.4 um; quantisation 1 um.
  double max_err = 0.0;
  for (const auto& p : mesh.vertices) max_err = std::max(max_err, std::abs((p.cast<double>() - c).norm() - r));
  EXPECT_LT(max_err, 0.02 * 0.01);
  const size_t edges = check_closed_oriented(mesh);
  // A sphere: Euler characteristic V - E + F = 2.
  EXPECT_EQ(long(mesh.vertices.size()) - long(edges) + long(mesh.triangles.size()), 2);
  check_welded(mesh);
  // Vertex normals: the SDF gradient, radial; triangles wound counter-clockwise seen from outside.
  ASSERT_EQ(mesh.normals.size(), mesh.vertices.size());
  double worst_deg = 0.0;
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d radial = (mesh.vertices[i].cast<double>() - c).normalized();
    worst_deg = std::max(worst_deg, std::acos(std::clamp(radial.dot(mesh.normals[i].cast<double>()), -1.0, 1.0)));
  }
  EXPECT_LT(worst_deg * 180.0 / M_PI, 1.0);
  for (const auto& t : mesh.triangles) {
    const Eigen::Vector3f n = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
    const Eigen::Vector3f centroid = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3.0f;
    EXPECT_GE(n.dot(centroid - c.cast<float>()), 0.0f);
  }
  EXPECT_EQ(mesh.colors.size(), mesh.vertices.size());
}

TEST(Mesh, TiltedPlaneVerticesAndColoursAreExact) {
  VoxelBlockGrid grid(mesh_params_1cm());
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
  const double offset = 0.0123;
  auto colour = [](const Eigen::Vector3d& p) {
    return Rgb8{std::uint8_t(std::clamp(128.0 + 400.0 * p.x(), 0.0, 255.0)), 7, 9};
  };
  fill_mesh_sdf(grid, [&](const Eigen::Vector3d& p) { return n.dot(p) - offset; }, {-0.2, -0.2, -0.2}, {0.2, 0.2, 0.2}, colour);
  const TriangleMesh mesh = extract_mesh(grid);
  ASSERT_GT(mesh.triangles.size(), 500u);
  for (size_t i = 0; i < mesh.vertices.size(); ++i) {
    const Eigen::Vector3d p = mesh.vertices[i].cast<double>();
    // A linear SDF is interpolated exactly: only float rounding and the 1/32767 quantisation remain.
    EXPECT_NEAR(n.dot(p) - offset, 0.0, 1e-5);
    EXPECT_NEAR(mesh.normals[i].cast<double>().dot(n), 1.0, 1e-4);
    EXPECT_NEAR(mesh.colors[i].r, colour(p).r, 2);
    EXPECT_EQ(mesh.colors[i].g, 7);
  }
  check_welded(mesh);
}

// A random field whose outer layer is free space: every cell configuration occurs, ambiguous faces included, and
// the surface must still close up, within and across blocks.
TEST(Mesh, RandomFieldGivesClosedOrientedSurface) {
  VoxelBlockGrid grid(mesh_params_1cm());
  std::mt19937 rng(7);
  std::uniform_real_distribution<float> u(-1.0f, 1.0f);
  const int n = 3 * HF_BLOCK_SIZE;  // 3 x 3 x 3 blocks
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        VoxelBlock* b = grid.allocate({i >> 3, j >> 3, k >> 3});
        Voxel& v = b->voxels[hf_voxel_index(i & 7, j & 7, k & 7)];
        const bool border = i == 0 || j == 0 || k == 0 || i == n - 1 || j == n - 1 || k == n - 1;
        float s = border ? 0.5f : u(rng);
        if (s == 0.0f) s = 0.1f;
        v.sdf = hf_quantise_sdf(s);
        v.weight = hf_quantise_weight(1.0f);
      }
  const TriangleMesh mesh = extract_mesh(grid);
  ASSERT_GT(mesh.triangles.size(), 5000u);
  ASSERT_NO_THROW(mesh.validate());
  check_closed_oriented(mesh);
  // Welded: exactly one vertex per crossed grid edge.
  size_t crossed = 0;
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        for (int a = 0; a < 3; ++a) {
          const int i2 = i + (a == 0), j2 = j + (a == 1), k2 = k + (a == 2);
          if (i2 >= n || j2 >= n || k2 >= n) continue;
          crossed += (grid.voxel(i, j, k)->sdf < 0) != (grid.voxel(i2, j2, k2)->sdf < 0);
        }
  EXPECT_EQ(mesh.vertices.size(), crossed);
  // Deterministic.
  const TriangleMesh again = extract_mesh(grid);
  EXPECT_EQ(again.vertices, mesh.vertices);
  EXPECT_EQ(again.triangles, mesh.triangles);
}

TEST(Mesh, MinimumWeightFilterAndUnobservedVoxels) {
  VoxelBlockGrid grid(mesh_params_1cm());
  const Eigen::Vector3d c(0.011, 0.013, 0.017);
  fill_mesh_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.1; }, c.array() - 0.2, c.array() + 0.2, nullptr,
       2.0f);
  const size_t full = extract_mesh(grid).triangles.size();
  ASSERT_GT(full, 100u);
  MeshOptions opts;
  opts.min_weight = 2.0f;
  EXPECT_EQ(extract_mesh(grid, opts).triangles.size(), full);
  opts.min_weight = 2.5f;
  EXPECT_EQ(extract_mesh(grid, opts).triangles.size(), 0u);
  // Unobserving the voxels of the upper half opens the sphere: a border appears, no surface next to unseen space.
  for (auto& [coord, block] : grid.blocks())
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x)
          if ((8 * coord.z + z + 0.5) * 0.01 > c.z()) block->voxels[hf_voxel_index(x, y, z)].weight = 0;
  const TriangleMesh half = extract_mesh(grid);
  EXPECT_GT(half.triangles.size(), full / 3);
  EXPECT_LT(half.triangles.size(), 2 * full / 3);
  for (const auto& p : half.vertices) EXPECT_LT(p.z(), c.z() + 0.01);
  opts.min_weight = -1.0f;
  EXPECT_THROW(extract_mesh(grid, opts), Error);
}

TEST(Mesh, StreamedOutBlocksAreMeshedIdentically) {
  VoxelBlockGrid grid(mesh_params_1cm());
  const Eigen::Vector3d c(0.0131, -0.0217, 0.0073);
  fill_mesh_sdf(grid, [&](const Eigen::Vector3d& p) { return (p - c).norm() - 0.2; }, c.array() - 0.3, c.array() + 0.3,
       [](const Eigen::Vector3d& p) { return Rgb8{std::uint8_t(100 + 300 * p.x()), 50, 60}; });
  const TriangleMesh before = extract_mesh(grid);
  BlockStore store;
  // Park every block with x >= 0 (half the map, including blocks next to resident ones).
  const size_t moved = stream_out(grid, store, Eigen::Vector3d(-10.0, 0.0, 0.0), 10.0);
  ASSERT_GT(moved, 10u);
  ASSERT_GT(grid.block_count(), 10u);
  const TriangleMesh mixed = extract_mesh(grid, store);
  EXPECT_EQ(mixed.vertices, before.vertices);
  EXPECT_EQ(mixed.triangles, before.triangles);
  EXPECT_EQ(mixed.colors, before.colors);
  EXPECT_EQ(mixed.normals, before.normals);
  // Grid alone misses the streamed half.
  EXPECT_LT(extract_mesh(grid).triangles.size(), before.triangles.size());
  stream_in_all(grid, store);
  const TriangleMesh back = extract_mesh(grid);
  EXPECT_EQ(back.vertices, before.vertices);
  EXPECT_EQ(back.triangles, before.triangles);
}

TEST(Mesh, BinaryPlyRoundTrip) {
  VoxelBlockGrid grid(mesh_params_1cm());
  fill_mesh_sdf(grid, [](const Eigen::Vector3d& p) { return p.norm() - 0.1; }, {-0.2, -0.2, -0.2}, {0.2, 0.2, 0.2});
  const TriangleMesh mesh = extract_mesh(grid);
  const std::string path = (std::filesystem::temp_directory_path() / "hf_test_mesh_sphere.ply").string();
  write_ply(path, mesh);
  const TriangleMesh read = read_ply_mesh(path);
  std::filesystem::remove(path);
  EXPECT_EQ(read.vertices, mesh.vertices);
  EXPECT_EQ(read.normals, mesh.normals);
  EXPECT_EQ(read.colors, mesh.colors);
  EXPECT_EQ(read.triangles, mesh.triangles);
}

TEST(Mesh, EmptyGridGivesEmptyMesh) {
  VoxelBlockGrid grid(mesh_params_1cm());
  const TriangleMesh mesh = extract_mesh(grid);
  EXPECT_TRUE(mesh.vertices.empty());
  EXPECT_TRUE(mesh.triangles.empty());
}

}  // namespace
}  // namespace hf::fusion
