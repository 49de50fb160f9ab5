// fusion/opencl/device_voxel_grid.h against the CPU's integrate() (fusion/integrate.h), voxel by voxel, and its
// failure modes. Every test skips with a message when no OpenCL platform is installed; in CI they run on PoCL.
#include "fusion/opencl/device_voxel_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <utility>

#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "registration/frame_pyramid.h"
#include "registration/opencl/device_pyramid.h"
#include "registration/opencl/opencl_backend.h"
#include "core/opencl/opencl_context.h"
#include "registration/registration.h"
#include "slam/pipeline.h"

namespace hf::fusion {
namespace {

std::shared_ptr<opencl::Context> context() {
  if (opencl::list_devices().empty()) return nullptr;
  return opencl::Context::shared();
}

#define HF_CONTEXT_OR_SKIP(ctx)                                                                            \
  const std::shared_ptr<opencl::Context> ctx = context();                                                  \
  if (!ctx) {                                                                                              \
    GTEST_SKIP() << "no OpenCL platform found (install pocl-opencl-icd): device fusion is not tested";     \
  }

PinholeCamera small_camera() { return PinholeCamera::preset("ros").scaled(2); }  // 160x120

VolumeParams params_1cm(size_t capacity = 1 << 14) {
  VolumeParams p;
  p.voxel_m = 0.01;
  p.truncation_vox = 4.0;
  p.capacity_blocks = capacity;
  return p;
}

datasets::SyntheticSequence room(int frames) {
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = frames;
  options.camera = small_camera();
  return datasets::SyntheticSequence(options);
}

struct Agreement {
  size_t blocks = 0, voxels = 0, identical = 0, max_sdf_steps = 0, max_colour = 0, weight_differs = 0;
  bool same_blocks = false;
};

// Voxel by voxel. sdf in quantisation steps (1/32767 of mu), colour in units.
Agreement compare(const VoxelBlockGrid& a, const VoxelBlockGrid& b) {
  Agreement out;
  const auto ca = a.block_coords(), cb = b.block_coords();
  out.same_blocks = ca == cb;
  out.blocks = ca.size();
  for (const BlockCoord& c : ca) {
    const VoxelBlock* x = a.find(c);
    const VoxelBlock* y = b.find(c);
    if (y == nullptr) continue;
    for (int i = 0; i < HF_VOXELS_PER_BLOCK; ++i) {
      const Voxel& u = x->voxels[size_t(i)];
      const Voxel& v = y->voxels[size_t(i)];
      ++out.voxels;
      out.identical += std::memcmp(&u, &v, sizeof(Voxel)) == 0;
      out.max_sdf_steps = std::max<size_t>(out.max_sdf_steps, size_t(std::abs(int(u.sdf) - int(v.sdf))));
      out.max_colour = std::max<size_t>(
          {out.max_colour, size_t(std::abs(int(u.r) - int(v.r))), size_t(std::abs(int(u.g) - int(v.g))),
           size_t(std::abs(int(u.b) - int(v.b)))});
      out.weight_differs += u.weight != v.weight;
    }
  }
  return out;
}

// The device's voxels equal the CPU's where the arithmetic is the same: with cl_khr_fp64 and correctly rounded
// division (PoCL) bit for bit; otherwise the band geometry is float, the blocks may differ at band edges and a voxel
// by one sdf step or colour unit (the rounding of its quantised average).
void expect_agreement(const VoxelBlockGrid& cpu, const VoxelBlockGrid& device, bool fp64) {
  const Agreement ag = compare(cpu, device);
  ASSERT_GT(ag.blocks, 50u);
  if (fp64) {
    EXPECT_TRUE(ag.same_blocks);
    EXPECT_EQ(ag.identical, ag.voxels) << "max sdf difference " << ag.max_sdf_steps << " steps";
  } else {
    EXPECT_LE(ag.max_sdf_steps, 1u);
    EXPECT_LE(ag.max_colour, 1u);
    EXPECT_EQ(ag.weight_differs, 0u);
  }
}

void integrate_both(bool point_to_plane) {
  const auto ctx = context();
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  const auto seq = room(9);
  IntegrateParams ip;
  ip.point_to_plane = point_to_plane;
  VoxelBlockGrid cpu(volume), mirror(volume);
  DeviceVoxelGrid device(volume, ctx);
  for (int i = 0; i < 3; ++i) {
    const auto f = seq.frame(i * 4);
    const IntegrateStats a = integrate(cpu, f.depth, f.color, camera, f.T_world_camera, ip);
    const IntegrateStats b = device.integrate(f.depth, f.color, camera, f.T_world_camera, ip);
    EXPECT_EQ(b.pixels_used, a.pixels_used);
    EXPECT_EQ(b.blocks_allocated, a.blocks_allocated);
    EXPECT_EQ(b.blocks_visible, a.blocks_visible);
    if (ctx->info().has_fp64) {
      EXPECT_EQ(b.voxels_updated, a.voxels_updated);
    }
    device.read_last_frame_into(mirror);  // a host copy that follows the device frame by frame
  }
  EXPECT_EQ(device.block_count(), cpu.block_count());
  VoxelBlockGrid whole(volume);
  EXPECT_EQ(device.read_into(whole), device.block_count());
  expect_agreement(cpu, whole, ctx->info().has_fp64);
  expect_agreement(cpu, mirror, ctx->info().has_fp64);
}

TEST(DeviceVoxelGrid, ProjectiveIntegrateMatchesCpuVoxelByVoxel) {
  HF_CONTEXT_OR_SKIP(ctx);
  integrate_both(false);
}

TEST(DeviceVoxelGrid, PointToPlaneIntegrateMatchesCpuVoxelByVoxel) {
  HF_CONTEXT_OR_SKIP(ctx);
  integrate_both(true);
}

// A host map changed on the host (here: fused on the CPU) loaded onto the device and fused on there goes on
// exactly as the CPU would.
TEST(DeviceVoxelGrid, LoadedHostMapContinuesAsOnTheCpu) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  const auto seq = room(5);
  VoxelBlockGrid cpu(volume);
  const auto f0 = seq.frame(0), f1 = seq.frame(4);
  integrate(cpu, f0.depth, f0.color, camera, f0.T_world_camera);
  DeviceVoxelGrid device(volume, ctx);
  device.load(cpu);
  EXPECT_EQ(device.block_count(), cpu.block_count());
  integrate(cpu, f1.depth, f1.color, camera, f1.T_world_camera);
  device.integrate(f1.depth, f1.color, camera, f1.T_world_camera);
  VoxelBlockGrid back(volume);
  device.read_into(back);
  expect_agreement(cpu, back, ctx->info().has_fp64);
}

// The device raycast (fusion/opencl/raycast.cl) against raycast() on the same map, with the room fused from five
// noisy frames and cast from a sixth pose: both march the same field and refine the crossing to 0.001 voxel, so
// where both hit the depths agree to far below a voxel and the normals (central differences at the hit) to a
// fraction of a degree. Hits and misses differ only where the two sampling patterns differ (the CPU also jumps
// empty 4^3-block regions, the device one block at a time): at silhouettes and the fringe of the observed volume,
// the class raycast()'s own skip_blocks / depth_hint tests allow (0.1-0.5 % of the pixels). Measured on PoCL, with
// and without a depth hint: no pixel differs in hit or miss, depths within 2.2e-5 m, no normal 0.5 degrees apart;
// shading and colour (trilinear, 8 bits) within one level.
TEST(DeviceVoxelGrid, RaycastMatchesTheCpuRaycast) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = 12;
  options.camera = camera;
  options.noise_enabled = true;
  const datasets::SyntheticSequence seq(options);
  VoxelBlockGrid cpu(volume);
  for (int i = 0; i < 5; ++i) {
    const auto f = seq.frame(2 * i);
    integrate(cpu, f.depth, f.color, camera, f.T_world_camera);
  }
  // The host map loaded onto the device (its surface-free flags copied), and the same frames fused there (the
  // flags its integrate keeps).
  DeviceVoxelGrid device(volume, ctx), fused(volume, ctx);
  device.load(cpu);
  for (int i = 0; i < 5; ++i) {
    const auto f = seq.frame(2 * i);
    fused.integrate(f.depth, f.color, camera, f.T_world_camera);
  }
  RaycastOptions ro;
  // Cast from an unfused pose without a hint, and from a fused frame's pose with its depth as the hint (the
  // pipeline's tracking raycast: each ray searches around the measured depth first); surface-free blocks walked
  // and skipped.
  const auto hinted = seq.frame(8);
  for (int c = 0; c < 6; ++c) {
    const bool hint = (c & 1) != 0, skip = (c & 2) != 0, on_fused = c >= 4;
    const SE3 pose = hint ? hinted.T_world_camera : seq.frame(11).T_world_camera;
    RaycastOptions o = ro;
    o.skip_blocks = skip || on_fused;
    if (hint) o.depth_hint = &hinted.depth;
    const RaycastResult a = raycast(cpu, camera, pose, o);
    RaycastResult b;
    (on_fused ? fused : device).raycast(camera, pose, o, &b);
    ASSERT_EQ(b.depth.width(), camera.width);
    ASSERT_EQ(b.shaded.width(), camera.width);
    long both = 0, one = 0, depth_off = 0, normal_off = 0, normals = 0, shade_off = 0, colour_off = 0;
    double max_depth = 0.0;
    for (int y = 0; y < camera.height; ++y)
      for (int x = 0; x < camera.width; ++x) {
        const bool ha = a.depth(x, y) > 0.0f, hb = b.depth(x, y) > 0.0f;
        if (ha != hb) {
          ++one;
          continue;
        }
        if (!ha) continue;
        ++both;
        const double dd = std::fabs(double(a.depth(x, y)) - double(b.depth(x, y)));
        max_depth = std::max(max_depth, dd);
        depth_off += dd > 1e-4;  // 0.01 voxel
        const hf_float4 na = a.normals(x, y), nb = b.normals(x, y);
        EXPECT_EQ(b.vertices(x, y).w, 1.0f);
        shade_off += std::abs(int(a.shaded(x, y).r) - int(b.shaded(x, y).r)) > 1;  // grey levels
        const Rgb8 ca = a.color(x, y), cb = b.color(x, y);
        colour_off += std::max({std::abs(ca.r - cb.r), std::abs(ca.g - cb.g), std::abs(ca.b - cb.b)}) > 1;
        if (na.w == 0.0f || nb.w == 0.0f) {
          normal_off += na.w != nb.w;
          continue;
        }
        ++normals;
        normal_off += hf_dot3(na, nb) < std::cos(0.5 * 3.14159265358979 / 180.0);
      }
    std::printf("raycast (hint %d, skip %d, %s map): %ld pixels hit on both, %ld on one, %ld depths > 0.01 voxel "
                "apart (max %.2e m), %ld normals > 0.5 deg apart of %ld\n", int(hint), int(o.skip_blocks),
                on_fused ? "device-fused" : "loaded", both, one, depth_off, max_depth, normal_off, normals);
    EXPECT_GT(both, long(camera.width) * camera.height / 2);
    EXPECT_EQ(b.hit_count, int(std::count_if(b.depth.data(), b.depth.data() + b.depth.width() * b.depth.height(),
                                             [](float d) { return d > 0.0f; })));
    EXPECT_LE(one, long(camera.width) * camera.height / 200);
    EXPECT_LE(depth_off, both / 200);
    EXPECT_LE(normal_off, both / 200);
    EXPECT_LE(shade_off, both / 200);
    EXPECT_LE(colour_off, both / 200);
  }
  const SE3 pose = seq.frame(11).T_world_camera;
  RaycastResult b;
  // A bad pose or options: hf::Error, as raycast().
  const SE3 nan_pose(Eigen::Quaterniond::Identity(), Eigen::Vector3d(std::numeric_limits<double>::quiet_NaN(), 0, 0));
  EXPECT_THROW(device.raycast(camera, nan_pose, ro, &b), Error);
  RaycastOptions bad = ro;
  bad.step_fraction = 1.5;
  EXPECT_THROW(device.raycast(camera, pose, bad, &b), Error);
  const DepthImage small(camera.width / 2, camera.height / 2, 1.0f);
  bad = ro;
  bad.depth_hint = &small;  // not the camera's size
  EXPECT_THROW(device.raycast(camera, pose, bad, &b), Error);
  // An empty map: every pixel a miss, as on the CPU.
  DeviceVoxelGrid empty(volume, ctx);
  empty.raycast(camera, pose, ro, &b);
  EXPECT_EQ(b.hit_count, 0);
  EXPECT_EQ(std::count_if(b.depth.data(), b.depth.data() + b.depth.width() * b.depth.height(),
                          [](float d) { return d != 0.0f; }),
            0);
}

// InfiniTAM stops silently when its block budget is exhausted; here the frame fails with the typed error, the
// pool holds exactly its capacity, and no voxel was updated (as the CPU's integrate()).
// The raycast's outputs stay on the device as the result's copies (core/device_copy.h): each copy holds exactly
// the read-back image, and a later raycast into another result never writes a copy a holder still keeps. A host
// raycast into the result writes its images in place and drops the copies.
TEST(DeviceVoxelGrid, RaycastCopiesHoldTheirImagesUntilDropped) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  const auto seq = room(6);
  DeviceVoxelGrid device(volume, ctx);
  VoxelBlockGrid cpu(volume);
  for (int i = 0; i < 3; ++i) {
    const auto f = seq.frame(i);
    device.integrate(f.depth, f.color, camera, f.T_world_camera);
    integrate(cpu, f.depth, f.color, camera, f.T_world_camera);
  }
  RaycastResult first, second;
  device.raycast(camera, seq.frame(1).T_world_camera, RaycastOptions{}, &first);
  device.raycast(camera, seq.frame(5).T_world_camera, RaycastOptions{}, &second);
  ASSERT_GT(first.hit_count, 0);
  EXPECT_EQ(first.device_copies.size(), 3u);
  auto device_image = [&](const VertexMap& host) {
    const size_t bytes = host.size() * sizeof(hf_float4);
    const cl::Buffer copy = ctx->resident(host.data(), bytes);
    VertexMap back(host.width(), host.height());
    if (copy() != nullptr) ctx->queue().enqueueReadBuffer(copy, CL_TRUE, 0, bytes, back.data());
    return std::pair{copy() != nullptr, back};
  };
  for (const RaycastResult* r : {&first, &second}) {
    for (const VertexMap* map : {&r->vertices, &r->normals}) {
      const auto [found, back] = device_image(*map);
      ASSERT_TRUE(found);
      EXPECT_EQ(std::memcmp(back.data(), map->data(), map->size() * sizeof(hf_float4)), 0);
    }
  }
  // The model pyramid's level 0 shares the raycast's buffers as its own images' copies: with the result's copies
  // dropped, the next raycast still writes new buffers, and the level's copies keep their images.
  opencl::DeviceFramePyramid pyramids(ctx);
  const FramePyramid model = pyramids.build_model(second.vertices, second.normals, camera, 3);
  second.device_copies.clear();
  RaycastResult third;
  device.raycast(camera, seq.frame(2).T_world_camera, RaycastOptions{}, &third);
  for (const VertexMap* map : {&model.levels[0].vertices, &model.levels[0].normals}) {
    const auto [found, back] = device_image(*map);
    ASSERT_TRUE(found);
    EXPECT_EQ(std::memcmp(back.data(), map->data(), map->size() * sizeof(hf_float4)), 0);
  }
  // The host raycast writes `first` in place: its copies go, nothing is bound for its images any more.
  raycast(cpu, camera, seq.frame(1).T_world_camera, RaycastOptions{}, &first);
  EXPECT_TRUE(first.device_copies.empty());
  EXPECT_FALSE(device_image(first.vertices).first);
  // A copied result carries no copies (its images live elsewhere).
  const RaycastResult copied = second;
  EXPECT_TRUE(copied.device_copies.empty());
  EXPECT_FALSE(device_image(copied.vertices).first);
}

// sdf aligns to the map: where the map lives on the device, publish_map lends its table and pool as the host
// mirror's copy and the OpenCL backend reads them in place (no flat copy built or uploaded). The same frame
// registered against the same map through the uploaded flat copy gives the same pose bit for bit (the same voxels,
// found through a table of the same geometry). While the copies are held the device map refuses to change.
TEST(DeviceVoxelGrid, SdfReadsTheDeviceMapInPlace) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  const auto seq = room(6);
  DeviceVoxelGrid device(volume, ctx);
  for (int i = 0; i < 4; ++i) {
    const auto f = seq.frame(i);
    device.integrate(f.depth, f.color, camera, f.T_world_camera);
  }
  VoxelBlockGrid mirror(volume);
  device.read_into(mirror);
  const auto ref = seq.frame(3), cur = seq.frame(5);
  FramePyramidOptions po;
  const FramePyramid current = build_frame_pyramid(cur.depth, &cur.color, camera, po);
  const SE3 truth = ref.T_world_camera.inverse() * cur.T_world_camera;
  RegistrationResult results[2];
  for (int resident = 0; resident < 2; ++resident) {
    auto backend = std::make_unique<opencl::OpenClReductionBackend>(ctx);
    const opencl::OpenClReductionBackend* counters = backend.get();
    const auto sdf = make_registration("sdf", default_registration_options("sdf"), std::move(backend));
    DeviceCopies copies;
    if (resident == 1) copies = device.publish_map(mirror);
    sdf->set_volume(&mirror, ref.T_world_camera);
    results[resident] = sdf->align(current, FramePyramid{}, SE3());
    EXPECT_EQ(counters->buffer_uploads(), resident == 1 ? 0u : 2u);
    EXPECT_EQ(counters->resident_binds() > 0, resident == 1);
    if (resident == 1) {
      const auto f = seq.frame(4);
      EXPECT_THROW(device.integrate(f.depth, f.color, camera, f.T_world_camera), Error);
      EXPECT_THROW(device.clear(), Error);
    }
  }
  EXPECT_EQ(results[0].status, results[1].status);
  EXPECT_EQ((results[0].T_ref_cur.matrix() - results[1].T_ref_cur.matrix()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LT((results[1].T_ref_cur.translation() - truth.translation()).norm(), 0.01);
  // The copies dropped, the map changes again.
  const auto f = seq.frame(4);
  EXPECT_NO_THROW(device.integrate(f.depth, f.color, camera, f.T_world_camera));
}

TEST(DeviceVoxelGrid, PoolExhaustionIsCapacityErrorWithNothingUpdated) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm(32);
  DeviceVoxelGrid device(volume, ctx);
  const auto f = room(1).frame(0);
  try {
    device.integrate(f.depth, f.color, small_camera(), f.T_world_camera);
    FAIL() << "expected CapacityError";
  } catch (const CapacityError& e) {
    EXPECT_NE(std::string(e.what()).find("capacity 32 blocks"), std::string::npos) << e.what();
  }
  EXPECT_EQ(device.block_count(), 32u);
  VoxelBlockGrid grid(volume);
  EXPECT_EQ(device.read_into(grid), 32u);
  for (const auto& [c, block] : grid.blocks())
    for (const Voxel& v : block->voxels) ASSERT_EQ(v.weight, 0) << "a voxel was updated by the failed frame";
}

// A probe bound of one entry cannot hold a frame's thousand blocks in a table of 2^15 entries without a collision:
// typed error naming the bound, never a block dropped in silence.
TEST(DeviceVoxelGrid, ProbeBoundIsCapacityError) {
  HF_CONTEXT_OR_SKIP(ctx);
  DeviceGridOptions options;
  options.max_probe = 1;
  DeviceVoxelGrid device(params_1cm(), ctx, options);
  const auto f = room(1).frame(0);
  try {
    device.integrate(f.depth, f.color, small_camera(), f.T_world_camera);
    FAIL() << "expected CapacityError";
  } catch (const CapacityError& e) {
    EXPECT_NE(std::string(e.what()).find("max_probe"), std::string::npos) << e.what();
  }
}

TEST(DeviceVoxelGrid, NanInfAndEmptyFramesChangeNothing) {
  HF_CONTEXT_OR_SKIP(ctx);
  const VolumeParams volume = params_1cm();
  const PinholeCamera camera = small_camera();
  DeviceVoxelGrid device(volume, ctx);
  const auto f = room(1).frame(0);
  device.integrate(f.depth, f.color, camera, f.T_world_camera);
  VoxelBlockGrid before(volume);
  device.read_into(before);
  for (float bad : {std::numeric_limits<float>::quiet_NaN(), std::numeric_limits<float>::infinity(), 0.0f, -1.0f}) {
    const DepthImage depth(camera.width, camera.height, bad);
    const IntegrateStats s = device.integrate(depth, ColorImage(), camera, f.T_world_camera);
    EXPECT_EQ(s.pixels_used, 0u) << bad;
    EXPECT_EQ(s.blocks_allocated, 0u) << bad;
    EXPECT_EQ(s.voxels_updated, 0u) << bad;
  }
  VoxelBlockGrid after(volume);
  device.read_into(after);
  const Agreement ag = compare(before, after);
  EXPECT_TRUE(ag.same_blocks);
  EXPECT_EQ(ag.identical, ag.voxels);
}

TEST(DeviceVoxelGrid, BadFrameAndOversizedPoolAreTypedErrors) {
  HF_CONTEXT_OR_SKIP(ctx);
  DeviceVoxelGrid device(params_1cm(), ctx);
  const PinholeCamera camera = small_camera();
  DepthImage wrong(camera.width + 1, camera.height);
  EXPECT_THROW(device.integrate(wrong, ColorImage(), camera, SE3::identity()), Error);
  VolumeParams huge = params_1cm(size_t(1) << 26);  // 256 GiB of voxels
  EXPECT_THROW(DeviceVoxelGrid(huge, ctx), DeviceMemoryError);
}

// The pipeline with backend opencl (integrate, the tracking raycast, the frame pyramid and the reductions on the
// device, the host map following it) against backend cpu on the same synthetic frames: with ground-truth poses the
// maps are the same bit for bit; tracked (combined), the poses differ only by float rounding (the reductions'
// order, the raycast's ray set-up, the bilateral filter's exp; tolerance 0.1 mm, 1e-4 rad: far below one voxel).
// On the device no map crosses to it between stages: the context's residency table finds every one.
TEST(DeviceVoxelGrid, PipelineOnTheDeviceMatchesTheCpuPipeline) {
  HF_CONTEXT_OR_SKIP(ctx);
  const PinholeCamera camera = small_camera();
  const auto seq = room(4);
  for (const std::string registration : {"groundtruth", "combined", "sdf"}) {
    std::vector<SE3> poses[2];
    VoxelBlockGrid maps[2] = {VoxelBlockGrid(params_1cm()), VoxelBlockGrid(params_1cm())};
    for (int b = 0; b < 2; ++b) {
      const opencl::Context::ResidencyStats before = ctx->residency_stats();
      slam::PipelineConfig config;
      config.registration = registration;
      config.backend = b == 0 ? "cpu" : "opencl";
      config.volume = params_1cm();
      slam::Pipeline pipeline(config, camera);
      for (int i = 0; i < 4; ++i) {
        const auto f = seq.frame(i);
        RgbdFrame frame;
        frame.index = size_t(i);
        frame.depth = f.depth;
        frame.color = f.color;
        frame.T_world_camera_gt = f.T_world_camera;
        const slam::FrameResult r = pipeline.process(frame);
        ASSERT_TRUE(r.integrated) << registration << " frame " << i;
        poses[b].push_back(r.T_world_camera);
      }
      // Integrate, the tracking raycast and the frame pyramid on the device, the reductions too.
      const auto devices = pipeline.stage_devices();
      const std::string device = b == 0 ? "cpu" : ctx->info().platform_name + " / " + ctx->info().device_name;
      for (const char* stage : {"integrate", "raycast", "preprocess"}) EXPECT_EQ(devices.at(stage), device) << stage;
      if (registration != "groundtruth") {
        EXPECT_EQ(devices.at("registration"), device);
      }
      // The frames' pyramids, the model maps and the model pyramid stay on the device between the stages: every
      // map the reduction and the model pyramid read was found there, none uploaded (core/device_copy.h).
      const opencl::Context::ResidencyStats after = ctx->residency_stats();
      if (b == 1) {
        EXPECT_EQ(after.misses - before.misses, 0u) << registration;
        if (registration != "groundtruth") {  // groundtruth casts no model maps
          EXPECT_GT(after.hits - before.hits, 0u) << registration;
        }
      }
      for (const auto& [c, block] : pipeline.map().blocks()) *maps[b].allocate(c) = *block;
    }
    for (size_t i = 0; i < poses[0].size(); ++i) {
      EXPECT_LT((poses[0][i].translation() - poses[1][i].translation()).norm(), 1e-4) << registration << " " << i;
      EXPECT_LT(Eigen::AngleAxisd(poses[0][i].rotation().transpose() * poses[1][i].rotation()).angle(), 1e-4);
    }
    if (registration == "groundtruth") expect_agreement(maps[0], maps[1], ctx->info().has_fp64);
  }
}

}  // namespace
}  // namespace hf::fusion
