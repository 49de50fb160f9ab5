// Fusion on an OpenCL device against the CPU (issue 20), room preset at 640x480, 1 cm, results in
// bench/results/opencl_fusion.md. The device is the one Context::shared() picks (HF_OPENCL_DEVICE, else the first
// GPU, else the first device); its name is in the benchmark context ("opencl_device").
//
//   BM_DeviceCopy               a float4 copy kernel over 2 x 256 MiB on the device: its memory bandwidth, counted as
//                               2 x 16 bytes per item (STREAM's copy)
//   BM_Integrate/<0 cpu|1 dev>  one integrate() per iteration after kWarmupFrames frames (steady state: most blocks
//                               exist), frames cycling as bench_fusion's BM_Integrate; counters as there: alloc_ms,
//                               update_ms, blocks visible, Mvox_updates/s (voxels of the visible blocks per second of
//                               alloc + update), update_GB/s (16 bytes read and written per voxel over update_ms) and
//                               its fraction of the copy bandwidth of the same device measured in this run
//   BM_ReadLastFrame            read_last_frame_into: what the pipeline's host copy of the map costs per frame
//   BM_Raycast/<0 cpu|1 dev>    the tracking raycast of the fused map from the next frames' poses, raycast() against
//                               DeviceVoxelGrid::raycast (range_ms, march_ms, read_ms: its stages)
//   BM_FlattenMap               fusion::flatten of the room's map: sdf's per-call copy on a device backend
//   BM_FramePyramid/<0 cpu|1 dev> the pipeline's tracking pyramid of one frame: build_frame_pyramid against
//                               DeviceFramePyramid (upload, kernels, read-back)
//   BM_Pipeline/<0 cpu|1 opencl|2 opencl, residency off>/<0 combined|1 sdf> whole slam::Pipeline frames per
//                               backend and registration: ms per stage and fps, over kPipelineFrames frames after
//                               the first; on the device also the maps bound in place / uploaded per frame
//                               (Context::residency_stats)
#include <benchmark/benchmark.h>

#include <chrono>
#include <cstdio>
#include <string_view>
#include <memory>
#include <string>
#include <vector>

#include "bench/room_frames.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/flat_block_map.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/opencl/device_voxel_grid.h"
#include "registration/frame_pyramid.h"
#include "registration/opencl/device_pyramid.h"
#include "core/opencl/opencl_context.h"
#include "slam/pipeline.h"

namespace hf::opencl {
std::string_view fusion_program_source();
}

namespace {

constexpr int kFrames = hf::bench::kRoomFrames;
constexpr int kWarmupFrames = 8;
constexpr int kPipelineFrames = 20;

using hf::bench::room_camera;
using hf::bench::room_frames;

hf::fusion::VolumeParams volume_1cm() {
  hf::fusion::VolumeParams params;
  params.voxel_m = 0.01;
  params.capacity_blocks = size_t(1) << 17;
  return params;
}

// Bytes/s of the device's copy kernel (best of `repetitions`), 2 x 16 bytes per item.
double device_copy_bandwidth(int repetitions) {
  auto ctx = hf::opencl::Context::shared();
  const size_t n = size_t(16) << 20;  // 16 Mi float4 = 256 MiB per buffer
  cl::Buffer a(ctx->context(), CL_MEM_READ_WRITE, n * 16), b(ctx->context(), CL_MEM_READ_WRITE, n * 16);
  cl::CommandQueue& q = ctx->queue();
  q.enqueueFillBuffer(a, 1.0f, 0, n * 16);
  q.enqueueFillBuffer(b, 0.0f, 0, n * 16);
  cl::Program program = ctx->program("fusion-fp32-bench", hf::opencl::fusion_program_source(),
                                     "-cl-fp32-correctly-rounded-divide-sqrt");
  cl::Kernel copy(program, "hf_copy_float4");
  copy.setArg(0, a);
  copy.setArg(1, b);
  q.enqueueNDRangeKernel(copy, cl::NullRange, cl::NDRange(n));  // warm-up
  q.finish();
  double best_s = 1e30;
  for (int rep = 0; rep < repetitions; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    q.enqueueNDRangeKernel(copy, cl::NullRange, cl::NDRange(n));
    q.finish();
    best_s = std::min(best_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
  }
  return 2.0 * 16.0 * double(n) / best_s;
}

double copy_bandwidth() {
  static const double bw = device_copy_bandwidth(5);
  return bw;
}

void BM_DeviceCopy(benchmark::State& state) {
  double bw = 0;
  for (auto _ : state) bw = device_copy_bandwidth(1);
  state.counters["GB/s"] = bw * 1e-9;
}
BENCHMARK(BM_DeviceCopy)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

void BM_Integrate(benchmark::State& state) {
  const bool device = state.range(0) == 1;
  const auto& frames = room_frames();
  const hf::fusion::VolumeParams params = volume_1cm();
  hf::fusion::VoxelBlockGrid grid(params);
  std::unique_ptr<hf::fusion::DeviceVoxelGrid> map;
  if (device) map = std::make_unique<hf::fusion::DeviceVoxelGrid>(params);
  auto run = [&](const hf::datasets::SyntheticFrame& f) {
    return device ? map->integrate(f.depth, f.color, room_camera(), f.T_world_camera)
                  : hf::fusion::integrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
  };
  for (int i = 0; i < kWarmupFrames; ++i) run(frames[size_t(i)]);
  const double bandwidth = device ? copy_bandwidth() : 0.0;
  int next = kWarmupFrames;
  double alloc_ms = 0, update_ms = 0, visible = 0;
  for (auto _ : state) {
    const hf::fusion::IntegrateStats s = run(frames[size_t(next)]);
    next = next + 1 < kFrames ? next + 1 : kWarmupFrames;
    alloc_ms += s.allocate_ms;
    update_ms += s.update_ms;
    visible += double(s.blocks_visible);
  }
  const double n = double(state.iterations());
  const double voxels = visible * HF_VOXELS_PER_BLOCK;
  state.counters["alloc_ms"] = alloc_ms / n;
  state.counters["update_ms"] = update_ms / n;
  state.counters["blocks_visible/frame"] = visible / n;
  state.counters["Mvox_updates/s"] = voxels / ((alloc_ms + update_ms) * 1e-3) * 1e-6;
  state.counters["update_GB/s"] = voxels * 16.0 / (update_ms * 1e-3) * 1e-9;
  if (device) {
    state.counters["copy_GB/s"] = bandwidth * 1e-9;
    state.counters["update_bw_fraction"] = voxels * 16.0 / (update_ms * 1e-3) / bandwidth;
  }
}
BENCHMARK(BM_Integrate)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_ReadLastFrame(benchmark::State& state) {
  const auto& frames = room_frames();
  const hf::fusion::VolumeParams params = volume_1cm();
  hf::fusion::DeviceVoxelGrid map(params);
  hf::fusion::VoxelBlockGrid host(params);
  for (int i = 0; i <= kWarmupFrames; ++i)
    map.integrate(frames[size_t(i)].depth, frames[size_t(i)].color, room_camera(), frames[size_t(i)].T_world_camera);
  size_t blocks = 0;
  for (auto _ : state) blocks = map.read_last_frame_into(host);
  state.counters["blocks"] = double(blocks);
}
BENCHMARK(BM_ReadLastFrame)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

// The tracking raycast of the map of kWarmupFrames + 1 frames, from the poses of the frames after them: the CPU's
// raycast() (surface-free blocks skipped, no hint, no colour or shading) against DeviceVoxelGrid::raycast (its
// range image, march and read-back in counters).
void BM_Raycast(benchmark::State& state) {
  const bool device = state.range(0) == 1;
  const auto& frames = room_frames();
  const hf::fusion::VolumeParams params = volume_1cm();
  hf::fusion::VoxelBlockGrid grid(params);
  for (int i = 0; i <= kWarmupFrames; ++i)
    hf::fusion::integrate(grid, frames[size_t(i)].depth, frames[size_t(i)].color, room_camera(),
                          frames[size_t(i)].T_world_camera);
  std::unique_ptr<hf::fusion::DeviceVoxelGrid> map;
  if (device) {
    map = std::make_unique<hf::fusion::DeviceVoxelGrid>(params);
    map->load(grid);
  }
  hf::fusion::RaycastOptions options;
  options.shade = false;
  options.color = false;
  hf::fusion::RaycastResult out;
  int next = kWarmupFrames + 1;
  double range_ms = 0, march_ms = 0, read_ms = 0, hits = 0;
  for (auto _ : state) {
    const hf::SE3& pose = frames[size_t(next)].T_world_camera;
    next = next + 1 < kFrames ? next + 1 : kWarmupFrames + 1;
    if (device) {
      map->raycast(room_camera(), pose, options, &out);
      const auto t = map->last_raycast_times();
      range_ms += t.range_ms, march_ms += t.march_ms, read_ms += t.read_ms;
    } else {
      hf::fusion::raycast(grid, room_camera(), pose, options, &out);
    }
    hits += out.hit_count;
  }
  const double n = double(state.iterations());
  state.counters["hits"] = hits / n;
  if (device) {
    state.counters["range_ms"] = range_ms / n;
    state.counters["march_ms"] = march_ms / n;
    state.counters["read_ms"] = read_ms / n;
  }
}
// Every pose once on both backends, so their hit counts compare.
BENCHMARK(BM_Raycast)
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->Iterations(kFrames - kWarmupFrames - 1);

// What sdf on a device backend pays per registration call in the pipeline (registration/sdf.h): the host map in
// the device's flat layout (fusion::flatten), here the map of all kFrames frames.
void BM_FlattenMap(benchmark::State& state) {
  const auto& frames = room_frames();
  hf::fusion::VoxelBlockGrid grid(volume_1cm());
  for (const auto& f : frames) hf::fusion::integrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
  size_t blocks = 0;
  for (auto _ : state) {
    const hf::fusion::FlatBlockMap flat = hf::fusion::flatten(grid);
    blocks = flat.blocks;
    benchmark::DoNotOptimize(flat.pool.data());
  }
  state.counters["blocks"] = double(blocks);
  state.counters["MiB"] = double(blocks) * sizeof(hf::fusion::VoxelBlock) / (1024.0 * 1024.0);
}
BENCHMARK(BM_FlattenMap)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

// The tracking pyramid of one 640x480 frame as the pipeline builds it (from 320x240: first_level 1, 3 levels,
// bilateral filter, colour): build_frame_pyramid against DeviceFramePyramid (upload, kernels, read-back).
void BM_FramePyramid(benchmark::State& state) {
  const bool device = state.range(0) == 1;
  const auto& frames = room_frames();
  hf::FramePyramidOptions options;
  options.first_level = 1;
  std::unique_ptr<hf::opencl::DeviceFramePyramid> builder;
  if (device) builder = std::make_unique<hf::opencl::DeviceFramePyramid>();
  int next = 0;
  for (auto _ : state) {
    const auto& f = frames[size_t(next)];
    next = (next + 1) % kFrames;
    const hf::FramePyramid p = device ? builder->build(f.depth, &f.color, room_camera(), options)
                                      : hf::build_frame_pyramid(f.depth, &f.color, room_camera(), options);
    benchmark::DoNotOptimize(p.levels.data());
  }
}
BENCHMARK(BM_FramePyramid)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(1.0);

void BM_Pipeline(benchmark::State& state) {
  hf::datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = kPipelineFrames + 1;
  const hf::datasets::SyntheticSequence seq(options);
  hf::slam::PipelineConfig config;
  config.registration = state.range(1) == 1 ? "sdf" : "combined";
  config.backend = state.range(0) >= 1 ? "opencl" : "cpu";
  config.volume = volume_1cm();
  const auto context = hf::opencl::Context::shared();
  context->set_residency_enabled(state.range(0) != 2);
  const hf::opencl::Context::ResidencyStats before = context->residency_stats();
  hf::slam::StageMs sum;
  double wall_ms = 0;
  int frames = 0;
  for (auto _ : state) {
    hf::slam::Pipeline pipeline(config, room_camera());
    for (int i = 0; i <= kPipelineFrames; ++i) {
      const auto f = seq.frame(i);
      hf::RgbdFrame frame;
      frame.index = size_t(i);
      frame.depth = f.depth;
      frame.color = f.color;
      frame.T_world_camera_gt = f.T_world_camera;
      const auto t0 = std::chrono::steady_clock::now();
      const hf::slam::FrameResult r = pipeline.process(frame);
      if (i == 0) continue;  // the first frame only initialises
      wall_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
      sum.preprocess += r.ms.preprocess, sum.track += r.ms.track, sum.integrate += r.ms.integrate;
      sum.raycast += r.ms.raycast, sum.keyframe += r.ms.keyframe, sum.loop += r.ms.loop;
      sum.reintegrate += r.ms.reintegrate;
      ++frames;
    }
  }
  const double n = double(frames);
  state.counters["preprocess_ms"] = sum.preprocess / n;
  state.counters["track_ms"] = sum.track / n;
  state.counters["integrate_ms"] = sum.integrate / n;
  state.counters["raycast_ms"] = sum.raycast / n;
  state.counters["other_ms"] = (sum.keyframe + sum.loop + sum.reintegrate) / n;
  state.counters["fps"] = 1e3 * n / wall_ms;
  const hf::opencl::Context::ResidencyStats after = context->residency_stats();
  const double all_frames = double(state.iterations()) * (kPipelineFrames + 1);
  state.counters["maps_bound_per_frame"] = double(after.hits - before.hits) / all_frames;
  state.counters["maps_uploaded_per_frame"] = double(after.misses - before.misses) / all_frames;
  context->set_residency_enabled(true);
}
BENCHMARK(BM_Pipeline)->ArgsProduct({{0, 1, 2}, {0, 1}})->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(1);

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (hf::opencl::list_devices().empty()) {
    std::fprintf(stderr, "bench_fusion_opencl: no OpenCL platform found (install pocl-opencl-icd)\n");
    return 1;
  }
  const auto context = hf::opencl::Context::shared();  // held for the run: every benchmark shares it
  const std::string device = context->info().platform_name + " / " + context->info().device_name;
  benchmark::AddCustomContext("opencl_device", device);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
