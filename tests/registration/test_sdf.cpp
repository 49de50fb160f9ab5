// sdf (registration/sdf.h) against a map: the frame aligned to a TSDF fused from other frames of the sequence at
// their true poses, the way the SLAM pipeline hands it its map. (Pairwise use, the OpenCL request and the hard
// cases are tested with every other method by the registry's tests: test_accuracy.cpp, test_hard_cases.cpp.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "core/error.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/flat_block_map.h"
#include "fusion/integrate.h"
#include "fusion/voxel_block_grid.h"
#include "reg_test_util.h"
#include "registration/dense_method.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/sdf_kernel.h"

namespace hf {
namespace {

struct MapCase {
  fusion::VoxelBlockGrid grid{[] {
    fusion::VolumeParams p;
    p.voxel_m = 0.01;
    p.capacity_blocks = 1 << 15;
    return p;
  }()};
  SE3 T_world_ref, T_world_cur;
  FramePyramid current;
};

// Frames 0..7 of the room fused at their true poses; frame 8 is the current one, frame 7 the reference camera.
MapCase make_map_case(bool noise) {
  datasets::SyntheticOptions o;
  o.preset = "room";
  o.frames = 9;
  o.camera = PinholeCamera::preset("ros").scaled(1);
  o.noise_enabled = noise;
  const datasets::SyntheticSequence seq(o);
  MapCase m;
  for (int i = 0; i < 8; ++i) {
    const datasets::SyntheticFrame f = seq.frame(i);
    fusion::integrate(m.grid, f.depth, f.color, o.camera, f.T_world_camera);
  }
  m.T_world_ref = seq.frame(7).T_world_camera;
  const datasets::SyntheticFrame cur = seq.frame(8);
  m.T_world_cur = cur.T_world_camera;
  FramePyramidOptions po;
  po.bilateral_filter = noise;
  m.current = build_frame_pyramid(cur.depth, &cur.color, o.camera, po);
  return m;
}

// The frame is placed in the map within a fraction of a voxel. Noise-free the floor is the map, not the frame:
// projective distances (fusion/integrate.h) averaged over 8 views at different angles bend the field off the
// surface by up to ~0.1 voxel (measured 0.99 mm / 0.024 deg), so 1.5 mm / 0.05 deg; with Kinect noise the map
// averages it over 8 frames and the current frame's own noise enters each row, the class of the noisy pairwise
// bound (3 mm / 0.2 deg, test_accuracy.cpp; measured 1.25 mm / 0.037 deg).
TEST(SdfRegistration, PlacesTheFrameInAFusedMap) {
  for (const bool noise : {false, true}) {
    MapCase m = make_map_case(noise);
    auto reg = make_registration("sdf");
    ASSERT_TRUE(reg->aligns_to_volume());
    reg->set_volume(&m.grid, m.T_world_ref);
    // No reference pyramid at all: the method reads the map only.
    const RegistrationResult r = reg->align(m.current, FramePyramid{}, SE3());
    test::expect_finite(r);
    EXPECT_EQ(r.status, RegistrationStatus::good) << r.message;
    const SE3 T_world_est = m.T_world_ref * r.T_ref_cur;
    const double et = test::translation_error_m(T_world_est, m.T_world_cur);
    const double er = test::rotation_error_deg(T_world_est, m.T_world_cur);
    std::printf("noise=%d: error %.3f mm %.4f deg, motion %.1f mm, inliers %.3f\n", int(noise), et * 1e3, er,
                (m.T_world_ref.inverse() * m.T_world_cur).translation().norm() * 1e3, r.inlier_ratio);
    EXPECT_LT(et, noise ? 3e-3 : 1.5e-3);
    EXPECT_LT(er, noise ? 0.2 : 0.05);
  }
}

// An empty map gives no rows: no_data / failed with the initial guess, never NaN; taking the map back makes the
// method pairwise again (it then needs a reference pyramid, and says so when it is empty).
TEST(SdfRegistration, EmptyMapAndNoMapGiveAStatus) {
  MapCase m = make_map_case(false);
  fusion::VoxelBlockGrid empty(m.grid.params());
  auto reg = make_registration("sdf");
  const SE3 guess = SE3::exp((Vector6d() << 0.01, 0, 0, 0.02, 0, 0).finished());
  reg->set_volume(&empty, m.T_world_ref);
  RegistrationResult r = reg->align(m.current, FramePyramid{}, guess);
  test::expect_finite(r);
  EXPECT_FALSE(r.usable());
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, guess), 1e-12);
  reg->set_volume(nullptr, SE3());
  r = reg->align(m.current, FramePyramid{}, guess);
  test::expect_finite(r);
  EXPECT_EQ(r.status, RegistrationStatus::no_data) << r.message;
}

// The two gathers of one cell, the host grid's (VolumeSampler, the cpu rows) and the flat hash a device reads
// (hf_sdf_pixel over the method's KernelBuffers, what the OpenCL kernel runs), give the same rows bit for bit on
// every pixel, with and without a weight gate: the arithmetic around them is one header's
// (registration/kernels/sdf_kernel.h), so the C++ and OpenCL backends can differ only in the order of their sums.
TEST(SdfRegistration, TheFlatMapGivesTheHostGridsRows) {
  MapCase m = make_map_case(true);
  long ungated_rows = 0;
  double ungated_weight = 0.0;
  // (min_voxel_weight, confidence_weight): off, the gate, the model's confidence.
  for (const auto& [min_weight, confidence] : {std::pair{0.0f, 0.0f}, {3.0f, 0.0f}, {0.0f, 6.0f}}) {
    RegistrationOptions options = default_registration_options("sdf");
    options.set("min_voxel_weight", double(min_weight));
    options.set("confidence_weight", double(confidence));
    options.set("finest_level_step", 1);
    test::MethodUnderTest method = test::method_under_test("sdf", options, make_backend("cpu"));
    method.registration->set_volume(&m.grid, m.T_world_ref);
    // 5 mm / ~0.3 degrees off the true pose, so rows land in every part of the band.
    const SE3 T = SE3::exp((Vector6d() << 0.003, -0.004, 0.005, 0.005, 0.002, -0.003).finished()) *
                  (m.T_world_ref.inverse() * m.T_world_cur);
    const ResidualProblem p = method.dense->level_problem(m.current, FramePyramid{}, 0, T);
    ASSERT_NE(p.maps[HF_SDF_IN_TABLE].buffer, nullptr);
    hf_reg_maps flat_maps = p.kernel_maps();
    flat_maps.map[HF_SDF_IN_TABLE] = static_cast<const float*>(p.maps[HF_SDF_IN_TABLE].buffer->contents().first);
    flat_maps.map[HF_SDF_IN_POOL] = static_cast<const float*>(p.maps[HF_SDF_IN_POOL].buffer->contents().first);
    const hf_reg_maps host_maps = p.kernel_maps();
    const hf_sdf_params params = *static_cast<const hf_sdf_params*>(p.params);
    long rows = 0, differ = 0;
    double weight = 0.0;
    for (int y = 0; y < p.height(); ++y) {
      for (int x = 0; x < p.width(); ++x) {
        hf_reg_row a{}, b{};
        const int na = p.kernel->pixel(x, y, &host_maps, p.camera, p.T_ref_cur, p.params, &a);
        const int nb = hf_sdf_pixel(x, y, &flat_maps, p.camera, p.T_ref_cur, params, &b);
        rows += na;
        weight += na == 1 ? a.w : 0.0f;
        differ += na != nb || (na == 1 && std::memcmp(&a, &b, sizeof a) != 0);
      }
    }
    EXPECT_GT(rows, 20000) << "min weight " << min_weight << ", confidence " << confidence;
    EXPECT_EQ(differ, 0) << "min weight " << min_weight << ", confidence " << confidence << ": of " << rows << " rows";
    // A table sized for fewer blocks than the grid holds (the grid grew after the kernel's parameters were set) is
    // refused, as is one that is not a power of two.
    EXPECT_THROW(fusion::flatten(m.grid, 16), Error);
    EXPECT_THROW(fusion::flatten(m.grid, 3 * fusion::flat_table_entries(m.grid.block_count())), Error);
    // The weight gate removes rows (the edges of the map saw fewer than 3 frames), on both paths alike; the
    // confidence keeps every row and lowers the weight of those whose cell was seen fewer than 6 times (8 frames
    // fused: the map's edges).
    if (min_weight == 0.0f && confidence == 0.0f) {
      ungated_rows = rows;
      ungated_weight = weight;
    } else if (min_weight > 0.0f) {
      EXPECT_LT(rows, ungated_rows);
    } else {
      EXPECT_EQ(rows, ungated_rows);
      EXPECT_LT(weight, ungated_weight);
      EXPECT_GT(weight, 0.5 * ungated_weight);
    }
  }
}

// The kernel's parameters for the one-cell tests below: the map at the identity, 1 cm voxels, mu 4 cm, Huber 1 cm.
hf_sdf_params one_cell_params() {
  hf_sdf_params p{};
  p.T_world_ref = to_transform12(SE3());
  p.inv_voxel_m = 100.0f;
  p.mu_m = 0.04f;
  p.max_abs_sdf = 0.9f;
  p.robust = robust_params(RobustKernel::huber, 0.01f, 0.01f, 5.0f);
  return p;
}

// The depth-noise weighting (SdfOptions::depth_noise_ref_m) on one cell of a field that rises along z: a row at depth
// z beyond ref keeps its Jacobian and residual and takes the weight s^2 w(s r), s = (ref / z)^2, w the robust
// kernel; at or nearer than ref the row is bit for bit the unweighted one. Distances 8 mm (inside Huber's 1 cm, so
// the weight is s^2 alone) and 30 mm (Huber 1/3 unweighted, 1 once scaled by s = 1/4).
TEST(SdfRegistration, DepthNoiseWeightScalesRowsAsRefOverZSquared) {
  hf_sdf_params p = one_cell_params();
  const float frac[3] = {0.5f, 0.5f, 0.5f};
  for (const float d_mid : {0.2f, 0.75f}) {
    float raw[8];  // corner c = x + 2 y + 4 z: d_mid -+ 0.1 on the near and far faces
    for (int c = 0; c < 8; ++c) raw[c] = std::round((d_mid + ((c >> 2) ? 0.1f : -0.1f)) * HF_SDF_SCALE);
    for (const float z : {1.0f, 1.5f, 3.0f}) {
      const hf_float4 v = hf_make_float4(0.01f, -0.02f, z, 1.0f);
      hf_reg_row off{}, on{};
      p.depth_noise_ref_m = 0.0f;
      ASSERT_EQ(hf_sdf_row(raw, frac, v, p, 0.0f, &off), 1);
      p.depth_noise_ref_m = 1.5f;
      ASSERT_EQ(hf_sdf_row(raw, frac, v, p, 0.0f, &on), 1);
      EXPECT_NEAR(off.r, d_mid * 0.04f, 1e-5f);
      if (z <= 1.5f) {
        EXPECT_EQ(std::memcmp(&off, &on, sizeof off), 0) << z;
        continue;
      }
      const float s = (1.5f / z) * (1.5f / z);
      EXPECT_EQ(std::memcmp(off.J, on.J, sizeof off.J), 0);
      EXPECT_EQ(off.r, on.r);
      const float huber_off = std::min(1.0f, 0.01f / std::abs(off.r));
      const float huber_on = std::min(1.0f, 0.01f / std::abs(s * off.r));
      EXPECT_NEAR(off.w, huber_off, 1e-6f);
      EXPECT_NEAR(on.w, s * s * huber_on, 1e-7f) << "d " << d_mid << " z " << z;
    }
  }
}

// The model's confidence (SdfOptions::confidence_weight, raw units in the kernel: HF_WEIGHT_SCALE per observation)
// on one cell: a row whose cell's least-seen voxel has weight w < ref keeps its Jacobian and residual and takes
// w / ref of the weight it has without the option; at w >= ref, and with the option off, the row is bit for bit the
// unweighted one.
TEST(SdfRegistration, ConfidenceWeighsRowsByTheCellsLeastWeight) {
  hf_sdf_params p = one_cell_params();
  const float frac[3] = {0.5f, 0.5f, 0.5f};
  float raw[8];
  for (int c = 0; c < 8; ++c) raw[c] = std::round((0.5f + ((c >> 2) ? 0.1f : -0.1f)) * HF_SDF_SCALE);
  const hf_float4 v = hf_make_float4(0.01f, -0.02f, 1.2f, 1.0f);
  hf_reg_row off{};
  ASSERT_EQ(hf_sdf_row(raw, frac, v, p, 16.0f, &off), 1);  // option off: the cell weight is not read
  p.confidence_weight_raw = 10.0f * HF_WEIGHT_SCALE;
  for (const float observations : {1.0f, 2.5f, 5.0f, 10.0f, 40.0f}) {
    hf_reg_row on{};
    ASSERT_EQ(hf_sdf_row(raw, frac, v, p, observations * HF_WEIGHT_SCALE, &on), 1);
    EXPECT_EQ(std::memcmp(off.J, on.J, sizeof off.J), 0);
    EXPECT_EQ(off.r, on.r);
    if (observations >= 10.0f) {
      EXPECT_EQ(std::memcmp(&off, &on, sizeof off), 0) << observations;
    } else {
      EXPECT_NEAR(on.w, off.w * observations / 10.0f, 1e-7f) << observations;
    }
  }
  // The option is validated.
  RegistrationOptions options = default_registration_options("sdf");
  for (const double bad : {-1.0, std::nan(""), 1e6}) {
    ASSERT_TRUE(options.set("confidence_weight", bad));
    EXPECT_THROW(options.validate(), Error) << bad;
  }
  ASSERT_TRUE(options.set("confidence_weight", 10.0));
  EXPECT_NO_THROW(options.validate());
}

}  // namespace
}  // namespace hf
