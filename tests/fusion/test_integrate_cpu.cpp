// The two spellings of integrate()'s loops (fusion/integrate_cpu.h). Phase 1: the AVX2 band ends equal the plain
// loop's on random rows, poses and depths, including invalid depth and coordinates beyond the packable range.
// Phase 2: the voxel-by-voxel loop is the shared kernel itself, and the AVX2 path gives every voxel the same bits
// on random blocks, frames and voxel contents, including the edge cases the kernel branches on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include <Eigen/Geometry>

#include "core/simd_avx2.h"
#include "fusion/integrate_cpu.h"

namespace hf::fusion {
namespace {

struct Case {
  int width = 0, height = 0;
  std::vector<float> depth, incidence;
  std::vector<hf_uint8> rgb;
  detail::FrameInputs in;
  detail::BlockFrame b{};
  VoxelBlock block;
};

// A block of 1-3 cm voxels somewhere around a small camera's view (often across the image border or the camera
// plane), a depth image near the block's depth with invalid pixels (0, negative, NaN, inf), optional point-to-plane
// factors (some 0 = unknown) and colour, and voxels holding anything a grid can hold.
Case random_case(std::mt19937& rng, bool with_incidence, bool with_rgb) {
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  Case c;
  c.width = 5 + int(rng() % 40);
  c.height = 2 + int(rng() % 30);
  c.in.K = hf_intrinsics{30.0f + 20.0f * U(rng), 30.0f + 20.0f * U(rng), 0.5f * c.width, 0.5f * c.height,
                         c.width, c.height};
  const float voxel = 0.01f + 0.02f * U(rng);
  c.in.mu = (1.0f + 5.0f * U(rng)) * voxel;
  c.in.max_weight = 1.0f + 200.0f * U(rng);
  c.in.w = 0.25f + 2.0f * U(rng);

  const Eigen::Quaternionf q(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f);
  const Eigen::Matrix3f R = q.normalized().toRotationMatrix();
  const float block_z = -0.05f + 0.6f * U(rng);
  const Eigen::Vector3f p0(0.4f * (U(rng) - 0.5f), 0.3f * (U(rng) - 0.5f), block_z);
  for (int a = 0; a < 3; ++a) {
    c.b.p0[a] = p0[a];
    c.b.s_x[a] = R(a, 0) * voxel;
    c.b.s_y[a] = R(a, 1) * voxel;
    c.b.s_z[a] = R(a, 2) * voxel;
  }

  const size_t n = size_t(c.width) * c.height;
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  c.depth.resize(n);
  for (float& d : c.depth) {
    const unsigned kind = rng() % 20;
    d = kind == 0 ? 0.0f : kind == 1 ? nan : kind == 2 ? inf : kind == 3 ? -0.3f
                                                                         : block_z + 4.0f * voxel * (U(rng) - 0.2f);
  }
  if (with_incidence) {
    c.incidence.resize(n);
    for (float& f : c.incidence) f = rng() % 5 == 0 ? 0.0f : 0.2f + 1.3f * U(rng);
  }
  if (with_rgb) {
    c.rgb.resize(3 * n);
    for (hf_uint8& v : c.rgb) v = hf_uint8(rng());
  }
  c.in.depth = c.depth.data();
  c.in.incidence = with_incidence ? c.incidence.data() : nullptr;
  c.in.rgb = with_rgb ? c.rgb.data() : nullptr;

  for (Voxel& v : c.block.voxels) {
    const unsigned kind = rng() % 6;
    v.sdf = hf_int16(kind == 0 ? 0 : kind == 1 ? 32767 : kind == 2 ? -32767 : int(rng() % 65535) - 32767);
    v.weight = hf_uint16(kind == 3 ? 0 : kind == 4 ? 65535 : rng() % 4000);
    v.r = hf_uint8(rng()), v.g = hf_uint8(rng()), v.b = hf_uint8(rng());
    v.flags = hf_uint8(rng() % 2);
  }
  return c;
}

bool same_bits(const Voxel& a, const Voxel& b) { return std::memcmp(&a, &b, sizeof(Voxel)) == 0; }
bool same_value(double a, double b) { return (std::isnan(a) && std::isnan(b)) || std::memcmp(&a, &b, sizeof a) == 0; }

// One row's band ends in both spellings.
struct BandBuffers {
  std::vector<double> ends;
  std::vector<std::int32_t> cells;
  std::vector<std::uint8_t> ok;
  detail::BandRow row{};
  explicit BandBuffers(int width) : ends(6 * size_t(width)), cells(6 * size_t(width)), ok(size_t(width)) {
    for (int i = 0; i < 3; ++i) {
      row.a[i] = ends.data() + size_t(i) * width;
      row.b[i] = ends.data() + size_t(3 + i) * width;
      row.cell_a[i] = cells.data() + size_t(i) * width;
      row.cell_b[i] = cells.data() + size_t(3 + i) * width;
    }
    row.ok = ok.data();
  }
};

TEST(IntegrateCpu, Avx2BandEndsAreTheLoops) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "this processor (or build) has no AVX2: only the plain loop runs here";
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  size_t ok_total = 0, rejected_by_range = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int width = 1 + int(rng() % 70);
    detail::BandFrame f;
    const Eigen::Matrix3d R =
        Eigen::Quaterniond(U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5, U(rng) - 0.5).normalized().toRotationMatrix();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) f.R[3 * i + j] = R(i, j);
    const double block = 0.02 + 0.1 * U(rng);
    // Every tenth pose sits next to the edge of the packable range (2^20 blocks), so some rays leave it.
    const double far = trial % 10 == 0 ? (double(1 << 20) - 2.0 - 3.0 * U(rng)) * block : 5.0;
    for (int i = 0; i < 3; ++i) f.t[i] = far * (i == 0 ? 1.0 : U(rng) - 0.5);
    f.inv_block = 1.0 / block;
    f.mu = 0.01 + 0.1 * U(rng);
    f.min_depth_m = 0.1, f.max_depth_m = 8.0;
    std::vector<double> ray_x(static_cast<size_t>(width));
    for (double& r : ray_x) r = 1.2 * (U(rng) - 0.5);
    const double ray_y = 1.2 * (U(rng) - 0.5);
    std::vector<float> depth(static_cast<size_t>(width));
    for (float& d : depth) {
      const unsigned kind = rng() % 12;
      d = kind == 0 ? 0.0f : kind == 1 ? nan : kind == 2 ? inf : kind == 3 ? -1.0f : kind == 4 ? 9.0f
          : kind == 5 ? 0.1f : float(0.05 + 8.0 * U(rng));
    }
    BandBuffers plain(width), simd(width);
    detail::band_row(depth.data(), width, ray_x.data(), ray_y, f, plain.row);
    detail::band_row_avx2(depth.data(), width, ray_x.data(), ray_y, f, simd.row);
    for (int u = 0; u < width; ++u) {
      ASSERT_EQ(plain.ok[u], simd.ok[u]) << "trial " << trial << " pixel " << u << " depth " << depth[u];
      const bool depth_in_range = depth[u] >= 0.1f && depth[u] <= 8.0f;
      ok_total += plain.ok[u];
      rejected_by_range += depth_in_range && !plain.ok[u];
      for (int i = 0; i < 3; ++i) {
        ASSERT_TRUE(same_value(plain.row.a[i][u], simd.row.a[i][u])) << "trial " << trial << " pixel " << u;
        ASSERT_TRUE(same_value(plain.row.b[i][u], simd.row.b[i][u])) << "trial " << trial << " pixel " << u;
        if (!plain.ok[u]) continue;
        EXPECT_EQ(plain.row.cell_a[i][u], simd.row.cell_a[i][u]);
        EXPECT_EQ(plain.row.cell_b[i][u], simd.row.cell_b[i][u]);
        EXPECT_EQ(plain.row.cell_a[i][u], std::int32_t(std::floor(plain.row.a[i][u])));
      }
    }
  }
  EXPECT_GT(ok_total, 3000u);
  EXPECT_GT(rejected_by_range, 10u);  // the packable-range test was exercised
}

TEST(IntegrateCpu, LoopIsTheSharedKernelVoxelByVoxel) {
  std::mt19937 rng(7);
  size_t updated_total = 0;
  int surface_cases = 0;
  for (int trial = 0; trial < 200; ++trial) {
    Case c = random_case(rng, trial % 2 == 1, trial % 3 != 0);
    VoxelBlock expected = c.block;
    int expected_updated = 0;
    bool expected_surface = false;  // an updated voxel holds an observed sdf <= 0
    for (int z = 0; z < 8; ++z)
      for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
          float p[3];
          for (int a = 0; a < 3; ++a)
            p[a] = ((c.b.p0[a] + float(z) * c.b.s_z[a]) + float(y) * c.b.s_y[a]) + float(x) * c.b.s_x[a];
          Voxel& v = expected.voxels[hf_voxel_index(x, y, z)];
          if (hf_integrate_voxel(&v, hf_make_float4(p[0], p[1], p[2], 1.0f), c.in.depth, c.in.incidence, c.in.rgb,
                                 c.in.K, c.in.mu, c.in.max_weight, c.in.w)) {
            ++expected_updated;
            expected_surface |= v.weight != 0 && v.sdf <= 0;
          }
        }
    bool wrote_surface = !expected_surface;
    EXPECT_EQ(detail::update_block(c.block.voxels.data(), c.b, c.in, &wrote_surface), expected_updated);
    EXPECT_EQ(wrote_surface, expected_surface) << "trial " << trial;
    surface_cases += expected_surface ? 1 : 0;
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i)
      ASSERT_TRUE(same_bits(c.block.voxels[i], expected.voxels[i])) << "trial " << trial << " voxel " << i;
    updated_total += size_t(expected_updated);
  }
  EXPECT_GT(updated_total, 200u * 20u);  // the cases exercise updates, not only rejections
  EXPECT_GT(surface_cases, 20);           // both answers of wrote_surface occur
  EXPECT_LT(surface_cases, 180);
}

TEST(IntegrateCpu, Avx2PathGivesTheLoopsBits) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "this processor (or build) has no AVX2: only the voxel loop runs here";
  std::mt19937 rng(11);
  size_t updated_total = 0, coloured = 0;
  int surface_cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    Case c = random_case(rng, trial % 2 == 1, trial % 3 != 0);
    VoxelBlock scalar = c.block, simd = c.block;
    bool surface_scalar = false, surface_simd = true;
    const int n_scalar = detail::update_block(scalar.voxels.data(), c.b, c.in, &surface_scalar);
    const int n_simd = detail::update_block_avx2(simd.voxels.data(), c.b, c.in, &surface_simd);
    ASSERT_EQ(n_simd, n_scalar) << "trial " << trial;
    ASSERT_EQ(surface_simd, surface_scalar) << "trial " << trial;
    surface_cases += surface_scalar ? 1 : 0;
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel& a = scalar.voxels[i];
      const Voxel& s = simd.voxels[i];
      ASSERT_TRUE(same_bits(a, s)) << "trial " << trial << " voxel " << i << ": loop (" << a.sdf << ", " << a.weight
                                   << ", " << int(a.r) << " " << int(a.g) << " " << int(a.b) << ", " << int(a.flags)
                                   << ") avx2 (" << s.sdf << ", " << s.weight << ", " << int(s.r) << " " << int(s.g)
                                   << " " << int(s.b) << ", " << int(s.flags) << ")";
      coloured += (a.flags & HF_VOXEL_FLAG_COLOUR) && !(c.block.voxels[i].flags & HF_VOXEL_FLAG_COLOUR);
    }
    updated_total += size_t(n_scalar);
  }
  EXPECT_GT(updated_total, 400u * 20u);
  EXPECT_GT(coloured, 100u);  // first colour samples happened
  EXPECT_GT(surface_cases, 40);  // both answers of wrote_surface occur
  EXPECT_LT(surface_cases, 360);
}

// The colour gather reads 32 bits around a pixel's three bytes: the first and last pixels of the image must come
// out right without reading outside it (ASan checks the latter).
TEST(IntegrateCpu, Avx2ColourOfTheFirstAndLastPixel) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "this processor (or build) has no AVX2: only the voxel loop runs here";
  for (int width : {1, 2, 3}) {
    Case c;
    c.width = width;
    c.height = width == 1 ? 2 : 1;
    c.in.K = hf_intrinsics{0.5f, 0.5f, 0.5f * c.width, 0.5f * c.height, c.width, c.height};
    c.depth.assign(size_t(c.width) * c.height, 1.0f);
    c.rgb.resize(3 * c.depth.size());
    for (size_t i = 0; i < c.rgb.size(); ++i) c.rgb[i] = hf_uint8(10 + 20 * i);
    c.in.depth = c.depth.data();
    c.in.rgb = c.rgb.data();
    c.in.mu = 0.04f, c.in.max_weight = 100.0f, c.in.w = 1.0f;
    // Voxels on the optical axis at z = 1 +- 1 cm span the image (a wide camera: fx = 0.5 px per unit x/z).
    for (int a = 0; a < 3; ++a) c.b.s_x[a] = c.b.s_y[a] = c.b.s_z[a] = 0.0f;
    c.b.p0[0] = -0.9f, c.b.p0[1] = -0.9f, c.b.p0[2] = 0.99f;
    c.b.s_x[0] = 0.25f, c.b.s_y[1] = 0.25f, c.b.s_z[2] = 0.003f;
    VoxelBlock scalar = c.block, simd = c.block;
    bool surface_scalar = false, surface_simd = false;
    const int n = detail::update_block(scalar.voxels.data(), c.b, c.in, &surface_scalar);
    EXPECT_GT(n, 0);
    EXPECT_EQ(detail::update_block_avx2(simd.voxels.data(), c.b, c.in, &surface_simd), n);
    EXPECT_EQ(surface_simd, surface_scalar);
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) ASSERT_TRUE(same_bits(scalar.voxels[i], simd.voxels[i])) << i;
  }
}

}  // namespace
}  // namespace hf::fusion
