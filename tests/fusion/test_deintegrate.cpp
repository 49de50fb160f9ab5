// Deintegration (fusion/deintegrate.h): deintegrate(integrate(frame)) restores every voxel within its quantisation
// step and collects the blocks it empties; integrating A and B and taking A out leaves what B alone gives; the
// weight cap's approximate inverse stays within its derived bound; the block loop is the per-voxel kernel bit for
// bit and inverts both spellings (plain, AVX2) of integrate's block update.
#include "fusion/deintegrate.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <unordered_map>
#include <vector>

#include "core/simd_avx2.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/integrate_cpu.h"
#include "fusion/kernels/integrate_kernels.h"

namespace hf::fusion {
namespace {

using Snapshot = std::unordered_map<BlockCoord, VoxelBlock, BlockCoordHash>;

Snapshot snapshot(const VoxelBlockGrid& grid) {
  Snapshot s;
  for (const auto& [c, block] : grid.blocks()) s.emplace(c, *block);
  return s;
}

bool observed(const VoxelBlock& block) {
  for (const Voxel& v : block.voxels)
    if (v.weight != 0) return true;
  return false;
}

VolumeParams deintegrate_params_1cm(float max_weight = 128.0f) {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.max_weight = max_weight;
  p.capacity_blocks = 1 << 15;
  return p;
}

// The room preset (with its sensor noise) seen by a 160x120 camera.
datasets::SyntheticSequence deintegrate_room(int frames) {
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = frames;
  options.camera = PinholeCamera::preset("ros").scaled(2);
  return datasets::SyntheticSequence(options);
}

void fuse(VoxelBlockGrid& grid, const datasets::SyntheticFrame& f, const PinholeCamera& camera,
          const IntegrateParams& params = {}) {
  integrate(grid, f.depth, f.color, camera, f.T_world_camera, params);
}

// Every block's surface_free flag is what its voxels say (as test_integrate's SurfaceFreeFlagsMatchTheVoxels).
void expect_surface_free_flags_exact(const VoxelBlockGrid& grid) {
  for (const auto& [c, block] : grid.blocks()) {
    if (!observed(*block)) continue;  // never observed: false (never skip) is the only safe value, also correct
    EXPECT_EQ(grid.surface_free(c), block_is_surface_free(*block)) << c.x << " " << c.y << " " << c.z;
  }
}

int sdf_steps(const Voxel& a, const Voxel& b) { return std::abs(int(a.sdf) - int(b.sdf)); }
int colour_units(const Voxel& a, const Voxel& b) {
  return std::max({std::abs(a.r - b.r), std::abs(a.g - b.g), std::abs(a.b - b.b)});
}

// Frames 0-3 fused, then frame 4 fused and taken out again: every voxel within its quantisation step of what it
// was. With weights W >= 1 and w = 1 the kernel header's bound (W_after / W) / 2 + 1/2 is at most 1 step (sdf) and
// 1 unit (colour); weights are exact. Blocks frame 4 created are collected; blocks that existed stay (except ones
// that held no observation at all, which deintegrate collects as well).
TEST(Deintegrate, RestoresEveryVoxelWithinItsQuantisationStep) {
  const auto seq = deintegrate_room(5);
  for (const bool point_to_plane : {false, true}) {
    SCOPED_TRACE(point_to_plane ? "point-to-plane" : "projective");
    IntegrateParams params;
    params.point_to_plane = point_to_plane;
    VoxelBlockGrid grid(deintegrate_params_1cm());
    for (int f = 0; f < 4; ++f) fuse(grid, seq.frame(f), seq.camera(), params);
    const Snapshot before = snapshot(grid);
    const auto frame = seq.frame(4);
    const IntegrateStats in = integrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera, params);
    ASSERT_GT(in.blocks_allocated, 0u);
    const DeintegrateStats out = deintegrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera, params);
    EXPECT_EQ(out.voxels_updated, in.voxels_updated);
    EXPECT_GE(out.blocks_released, in.blocks_allocated);

    size_t checked = 0, coloured = 0;
    for (const auto& [c, block] : grid.blocks()) {
      const auto it = before.find(c);
      ASSERT_NE(it, before.end()) << "a block frame 4 created survived";
      for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
        const Voxel& was = it->second.voxels[size_t(i)];
        const Voxel& now = block->voxels[size_t(i)];
        ASSERT_EQ(now.weight, was.weight);
        if (was.weight == 0) {
          EXPECT_EQ(std::memcmp(&now, &was, sizeof(Voxel)), 0);
          continue;
        }
        ++checked;
        ASSERT_LE(sdf_steps(now, was), 1);
        if (was.flags & HF_VOXEL_FLAG_COLOUR) {
          ++coloured;
          ASSERT_TRUE(now.flags & HF_VOXEL_FLAG_COLOUR);
          ASSERT_LE(colour_units(now, was), 1);
        }
      }
    }
    for (const auto& [c, block] : before)
      if (grid.find(c) == nullptr) {
        EXPECT_FALSE(observed(block)) << "an observed block was released";
      }
    EXPECT_GT(checked, 50000u);
    EXPECT_GT(coloured, 10000u);
    expect_surface_free_flags_exact(grid);

    // On an empty grid the frame was everything: nothing is left.
    VoxelBlockGrid alone(deintegrate_params_1cm());
    fuse(alone, frame, seq.camera(), params);
    const size_t blocks = alone.block_count();
    const DeintegrateStats gone = deintegrate(alone, frame.depth, frame.color, seq.camera(), frame.T_world_camera, params);
    EXPECT_EQ(gone.blocks_released, blocks);
    EXPECT_EQ(alone.block_count(), 0u);
  }
}

// Fusing A then B and taking A out leaves the field B alone gives: weights exact; sdf within 2 steps (the A+B
// average is within half a step; taking A out doubles that, 1 step, and both sides are rounded, 1/2 each); colour
// within 2 units where B alone has colour. Where A gave a voxel its first colour and B only carved it, A's colour
// stays (deintegrate.h): every voxel with a colour B alone does not give must be one of those, with A's colour.
TEST(Deintegrate, FusingAAndBThenTakingAOutLeavesB) {
  const auto seq = deintegrate_room(9);
  const auto a = seq.frame(2), b = seq.frame(8);
  VoxelBlockGrid both(deintegrate_params_1cm()), a_alone(deintegrate_params_1cm()), b_alone(deintegrate_params_1cm());
  fuse(a_alone, a, seq.camera());
  fuse(both, a, seq.camera());
  fuse(both, b, seq.camera());
  const DeintegrateStats out = deintegrate(both, a.depth, a.color, seq.camera(), a.T_world_camera);
  EXPECT_GT(out.blocks_released, 0u);
  fuse(b_alone, b, seq.camera());

  const Voxel unobserved{};
  auto voxel_of = [&](const VoxelBlockGrid& g, const BlockCoord& c, int i) {
    const VoxelBlock* block = g.find(c);
    return block ? block->voxels[size_t(i)] : unobserved;
  };
  size_t compared = 0, coloured = 0, stale_colour = 0;
  auto compare = [&](const BlockCoord& c) {
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel x = voxel_of(both, c, i), y = voxel_of(b_alone, c, i);
      ASSERT_EQ(x.weight, y.weight) << c.x << " " << c.y << " " << c.z << " voxel " << i;
      if (y.weight == 0) continue;
      ++compared;
      ASSERT_LE(sdf_steps(x, y), 2);
      if (y.flags & HF_VOXEL_FLAG_COLOUR) {
        ++coloured;
        ASSERT_TRUE(x.flags & HF_VOXEL_FLAG_COLOUR);
        ASSERT_LE(colour_units(x, y), 2);
      } else if (x.flags & HF_VOXEL_FLAG_COLOUR) {
        // A gave the voxel its first colour and B only carved it: A's colour stays (deintegrate.h).
        const Voxel first = voxel_of(a_alone, c, i);
        ASSERT_TRUE(first.flags & HF_VOXEL_FLAG_COLOUR);
        ASSERT_LE(colour_units(x, first), 1);
        ++stale_colour;
      }
    }
  };
  for (const BlockCoord& c : both.block_coords()) compare(c);
  for (const BlockCoord& c : b_alone.block_coords())
    if (both.find(c) == nullptr) compare(c);
  EXPECT_GT(compared, 50000u);
  EXPECT_GT(coloured, 10000u);
  EXPECT_GT(stale_colour, 0u);
  // Every block A's removal left without an observation is gone.
  for (const BlockCoord& c : blocks_touched_by(both.params(), a.depth, seq.camera(), a.T_world_camera)) {
    const VoxelBlock* block = both.find(c);
    if (block) {
      EXPECT_TRUE(observed(*block));
    }
  }
  expect_surface_free_flags_exact(both);
}

// The cap (max_weight 4): frames 0-5 bring most voxels to it; fusing frame 6 and taking it out restores voxels
// below the cap within a step and leaves voxels at the cap at weight W_max - w with sdf within the approximate
// inverse's bound 2 w^2 / (W_max^2 - w^2) = 2/15 of mu (plus the quantisation); fusing frame 6 again then gives
// back the voxels as they were after its first fusion, except where the inverse left [-1, 1] and was clamped.
// Which voxels frame 6 observes, and its observation d, come from fusing it alone (W = w: sdf = d to half a step).
TEST(Deintegrate, WeightCapGivesTheApproximateInverse) {
  const float cap = 4.0f, w = 1.0f;
  const auto seq = deintegrate_room(7);
  VoxelBlockGrid grid(deintegrate_params_1cm(cap)), alone(deintegrate_params_1cm(cap));
  for (int f = 0; f < 6; ++f) fuse(grid, seq.frame(f), seq.camera());
  const Snapshot before = snapshot(grid);
  const auto frame = seq.frame(6);
  fuse(grid, frame, seq.camera());
  fuse(alone, frame, seq.camera());
  const Snapshot fused = snapshot(grid);
  deintegrate(grid, frame.depth, frame.color, seq.camera(), frame.T_world_camera);

  // The stored value's half step grows by W_max / (W_max - w) in the inverse, and the result is rounded again.
  const double bound_steps = 2.0 * w * w / (cap * cap - w * w) * HF_SDF_SCALE + 0.5 * cap / (cap - w) + 0.5;
  const Voxel unobserved{};
  auto observation = [&](const BlockCoord& c, int i) {
    const VoxelBlock* block = alone.find(c);
    return block ? block->voxels[size_t(i)] : unobserved;
  };
  size_t at_cap = 0, below = 0;
  for (const auto& [c, block] : grid.blocks()) {
    const auto it = before.find(c);
    ASSERT_NE(it, before.end());
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel& was = it->second.voxels[size_t(i)];
      const Voxel& now = block->voxels[size_t(i)];
      if (observation(c, i).weight == 0) {
        ASSERT_EQ(std::memcmp(&now, &was, sizeof(Voxel)), 0);
        continue;
      }
      if (hf_voxel_weight(was) + w <= cap) {
        ++below;
        ASSERT_EQ(now.weight, was.weight);
        ASSERT_LE(sdf_steps(now, was), 1);
      } else {
        ++at_cap;
        ASSERT_EQ(hf_voxel_weight(now), cap - w);
        ASSERT_LE(sdf_steps(now, was), bound_steps);
      }
    }
  }
  EXPECT_GT(at_cap, 10000u);
  EXPECT_GT(below, 1000u);

  // integrate(deintegrate(v)) = v up to the quantisation (the inverse's half step times (W_max - w) / W_max, and
  // the rounding), at the cap as well, where the inverse (W_max D - w d) / (W_max - w) stayed within [-1, 1].
  fuse(grid, frame, seq.camera());
  size_t round_trips = 0;
  for (const auto& [c, block] : grid.blocks()) {
    const VoxelBlock& with_6 = fused.at(c);
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel& v = with_6.voxels[size_t(i)];
      ASSERT_EQ(block->voxels[size_t(i)].weight, v.weight);
      const double W = hf_voxel_weight(v), d = hf_voxel_sdf(observation(c, i));
      const double inverse = W > w ? (W * hf_voxel_sdf(v) - w * d) / (W - w) : 0.0;
      if (std::abs(inverse) > 1.0 - 1e-3) continue;
      ASSERT_LE(sdf_steps(block->voxels[size_t(i)], v), 1);
      ++round_trips;
    }
  }
  EXPECT_GT(round_trips, 10000u);
}

// A block in front of a small camera with a depth image near it, colour, and voxels of every kind a grid holds:
// unobserved (all zero) or observed with weights 1 .. 100 and any sdf and colour.
struct BlockCase {
  PinholeCamera camera;
  std::vector<float> depth;
  std::vector<hf_uint8> rgb;
  detail::FrameInputs in;
  detail::BlockFrame b{};
  VoxelBlock block;
};

BlockCase random_block(std::mt19937& rng) {
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  BlockCase c;
  const int width = 24, height = 18;
  c.in.K = hf_intrinsics{20.0f, 20.0f, 12.0f, 9.0f, width, height};
  const float voxel = 0.01f;
  c.in.mu = 0.04f;
  c.in.max_weight = 4095.0f;
  c.in.w = (rng() % 2) ? 1.0f : 0.5f;
  const Eigen::Matrix3f R =
      Eigen::Quaternionf(U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f, U(rng) - 0.5f).normalized().toRotationMatrix();
  for (int a = 0; a < 3; ++a) {
    c.b.p0[a] = a == 2 ? 0.5f : 0.05f * (U(rng) - 0.5f);
    c.b.s_x[a] = R(a, 0) * voxel;
    c.b.s_y[a] = R(a, 1) * voxel;
    c.b.s_z[a] = R(a, 2) * voxel;
  }
  c.depth.resize(size_t(width) * height);
  for (float& d : c.depth) d = rng() % 10 == 0 ? 0.0f : 0.5f + 0.12f * (U(rng) - 0.3f);
  c.rgb.resize(3 * c.depth.size());
  for (hf_uint8& v : c.rgb) v = hf_uint8(rng());
  c.in.depth = c.depth.data();
  c.in.rgb = c.rgb.data();
  for (Voxel& v : c.block.voxels) {
    if (rng() % 4 == 0) continue;  // unobserved
    v.sdf = hf_int16(int(rng() % 65535) - 32767);
    v.weight = hf_uint16(16 + rng() % 1585);  // 1 .. 100
    v.r = hf_uint8(rng()), v.g = hf_uint8(rng()), v.b = hf_uint8(rng());
    v.flags = hf_uint8(rng() % 2);
  }
  return c;
}

// deintegrate_block is hf_deintegrate_voxel voxel by voxel (the voxel centres stepped as integrate's loops do), and
// it inverts integrate's block update in both spellings within the kernel's bound: weight exact, sdf and colour
// within floor((W_after / W) / 2 + 1/2) (both spellings give the same bits, test_integrate_cpu).
TEST(Deintegrate, BlockLoopIsTheKernelAndInvertsBothSpellings) {
  std::mt19937 rng(11);
  size_t checked = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const BlockCase c = random_block(rng);
    std::vector<VoxelBlock> fused{c.block};
    bool surface = false;
    detail::update_block(fused[0].voxels.data(), c.b, c.in, &surface);
    if (cpu_has_avx2()) {
      fused.push_back(c.block);
      detail::update_block_avx2(fused[1].voxels.data(), c.b, c.in, &surface);
    }
    for (const VoxelBlock& start : fused) {
      VoxelBlock loop = start, reference = start;
      const int n = detail::deintegrate_block(loop.voxels.data(), c.b, c.in);
      int n_reference = 0;
      for (int z = 0; z < 8; ++z)
        for (int y = 0; y < 8; ++y)
          for (int x = 0; x < 8; ++x) {
            float p[3];
            for (int a = 0; a < 3; ++a)
              p[a] = ((c.b.p0[a] + float(z) * c.b.s_z[a]) + float(y) * c.b.s_y[a]) + float(x) * c.b.s_x[a];
            n_reference += hf_deintegrate_voxel(&reference.voxels[size_t(hf_voxel_index(x, y, z))],
                                                hf_make_float4(p[0], p[1], p[2], 1.0f), c.in.depth, nullptr,
                                                c.in.rgb, c.in.K, c.in.mu, c.in.w);
          }
      ASSERT_EQ(n, n_reference);
      ASSERT_EQ(std::memcmp(&loop, &reference, sizeof(VoxelBlock)), 0) << "trial " << trial;
      for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
        const Voxel& was = c.block.voxels[size_t(i)];
        const Voxel& now = loop.voxels[size_t(i)];
        const Voxel& mid = start.voxels[size_t(i)];
        ASSERT_EQ(now.weight, was.weight);
        if (was.weight == 0) {
          ASSERT_EQ(std::memcmp(&now, &was, sizeof(Voxel)), 0);
          continue;
        }
        const int bound = int(std::floor(0.5 * hf_voxel_weight(mid) / hf_voxel_weight(was) + 0.5 + 1e-3));
        ASSERT_LE(sdf_steps(now, was), bound) << "trial " << trial << " voxel " << i;
        if (was.flags & HF_VOXEL_FLAG_COLOUR) {
          ASSERT_LE(colour_units(now, was), bound);
        }
        checked += std::memcmp(&mid, &was, sizeof(Voxel)) != 0;
      }
    }
  }
  EXPECT_GT(checked, 10000u);
}

// The AVX2 spelling of the block loop gives the plain one's bits on random blocks with every edge case the kernel
// branches on: depth 0, negative, NaN, inf; point-to-plane factors (some unknown) or none; colour or none; voxels
// unobserved (with stray bits), below the observation weight (reset), at the raw maximum, with and without colour;
// observation weights from 0.25 to 2.25; blocks across the image border and the camera plane.
TEST(Deintegrate, Avx2BlockLoopIsThePlainOne) {
  if (!cpu_has_avx2()) GTEST_SKIP() << "this processor (or build) has no AVX2: only the plain loop runs here";
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> U(0.0f, 1.0f);
  const float nan = std::numeric_limits<float>::quiet_NaN(), inf = std::numeric_limits<float>::infinity();
  size_t updated = 0, resets = 0;
  for (int trial = 0; trial < 400; ++trial) {
    BlockCase c = random_block(rng);
    const int width = 5 + int(rng() % 30), height = 2 + int(rng() % 20);
    c.in.K = hf_intrinsics{15.0f + 20.0f * U(rng), 15.0f + 20.0f * U(rng), 0.5f * width, 0.5f * height, width,
                           height};
    c.in.w = 0.25f + 2.0f * U(rng);
    c.in.mu = 0.01f + 0.05f * U(rng);
    c.b.p0[2] = -0.05f + 0.6f * U(rng);
    c.depth.resize(size_t(width) * height);
    for (float& d : c.depth) {
      const unsigned kind = rng() % 16;
      d = kind == 0 ? 0.0f : kind == 1 ? nan : kind == 2 ? inf : kind == 3 ? -0.3f : c.b.p0[2] + 0.1f * (U(rng) - 0.3f);
    }
    std::vector<float> incidence;
    if (trial % 3 == 0) {
      incidence.resize(c.depth.size());
      for (float& f : incidence) f = rng() % 5 == 0 ? 0.0f : 0.2f + 1.3f * U(rng);
    }
    c.rgb.resize(3 * c.depth.size());
    for (hf_uint8& v : c.rgb) v = hf_uint8(rng());
    c.in.depth = c.depth.data();
    c.in.incidence = incidence.empty() ? nullptr : incidence.data();
    c.in.rgb = trial % 4 == 1 ? nullptr : c.rgb.data();
    for (Voxel& v : c.block.voxels) {
      const unsigned kind = rng() % 8;
      if (kind == 0) v = Voxel{hf_int16(rng()), 0, hf_uint8(rng()), 0, 0, hf_uint8(rng() % 2)};  // stray bits
      if (kind == 1) v.weight = hf_uint16(rng() % 40);                                          // <= 2.5
      if (kind == 2) v.weight = HF_WEIGHT_MAX_RAW;
    }
    VoxelBlock plain = c.block, simd = c.block;
    const int n_plain = detail::deintegrate_block(plain.voxels.data(), c.b, c.in);
    const int n_simd = detail::deintegrate_block_avx2(simd.voxels.data(), c.b, c.in);
    ASSERT_EQ(n_plain, n_simd) << "trial " << trial;
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      ASSERT_EQ(std::memcmp(&plain.voxels[size_t(i)], &simd.voxels[size_t(i)], sizeof(Voxel)), 0)
          << "trial " << trial << " voxel " << i;
      resets += c.block.voxels[size_t(i)].weight != 0 && plain.voxels[size_t(i)].weight == 0;
    }
    updated += size_t(n_plain);
  }
  EXPECT_GT(updated, 5000u);
  EXPECT_GT(resets, 500u);
}

// A frame fused at a wrong pose and moved by reintegrate() gives the field of fusing it at the right pose (weights
// exact, sdf within 2 steps: order of the two averages and the rounding of the removal).
TEST(Deintegrate, ReintegrateMovesAFrameToItsNewPose) {
  const auto seq = deintegrate_room(9);
  const auto a = seq.frame(4), b = seq.frame(0);
  const SE3 wrong = a.T_world_camera * SE3::exp((Vector6d() << 0.02, -0.01, 0.03, 0.05, 0.02, -0.04).finished());
  VoxelBlockGrid moved(deintegrate_params_1cm()), right(deintegrate_params_1cm());
  integrate(moved, a.depth, a.color, seq.camera(), wrong);
  fuse(moved, b, seq.camera());
  const ReintegrateStats stats = reintegrate(moved, a.depth, a.color, seq.camera(), wrong, a.T_world_camera);
  EXPECT_GT(stats.deintegrated.voxels_updated, 0u);
  EXPECT_GT(stats.integrated.voxels_updated, 0u);
  fuse(right, b, seq.camera());
  fuse(right, a, seq.camera());
  size_t compared = 0;
  for (const auto& [c, block] : right.blocks()) {
    const VoxelBlock* other = moved.find(c);
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel& y = block->voxels[size_t(i)];
      const Voxel x = other ? other->voxels[size_t(i)] : Voxel{};
      ASSERT_EQ(x.weight, y.weight);
      if (y.weight == 0) continue;
      ASSERT_LE(sdf_steps(x, y), 2);
      ++compared;
    }
  }
  for (const auto& [c, block] : moved.blocks())
    if (right.find(c) == nullptr) {
      EXPECT_FALSE(observed(*block));
    }
  EXPECT_GT(compared, 50000u);
}

// Bad sizes throw integrate's hf::Error before anything changes.
TEST(Deintegrate, SizeMismatchThrowsAndChangesNothing) {
  const auto seq = deintegrate_room(1);
  const auto f = seq.frame(0);
  VoxelBlockGrid grid(deintegrate_params_1cm());
  fuse(grid, f, seq.camera());
  const Snapshot before = snapshot(grid);
  const ColorImage wrong_colour(8, 8);
  EXPECT_THROW(deintegrate(grid, f.depth, wrong_colour, seq.camera(), f.T_world_camera), Error);
  EXPECT_THROW(deintegrate(grid, f.depth, f.color, PinholeCamera::preset("ros"), f.T_world_camera), Error);
  const Snapshot after = snapshot(grid);
  ASSERT_EQ(after.size(), before.size());
  for (const auto& [c, block] : before) EXPECT_EQ(std::memcmp(&after.at(c), &block, sizeof(VoxelBlock)), 0);
}

}  // namespace
}  // namespace hf::fusion
