// Fusion benchmarks on the `room` preset at 640x480 (noisy depth, as a sensor gives it).
//
//   BM_Integrate/<voxel mm>   one integrate() per iteration, frames cycling through the sequence after a warm-up
//                             of kWarmupFrames frames (so the map is in steady state: most blocks already exist).
//   BM_Deintegrate/<voxel mm> one deintegrate() per iteration (fusion/deintegrate.h) on the same map after every frame
//                             of the cycle was fused: a fused frame is taken out, then fused back untimed (so the
//                             map stays the same); counters split it into find / update / release ms.
//   BM_StreamCopy             STREAM "copy" a[i] = b[i] over 2 x 256 MiB in parallel on all cores: the machine's
//                             memory bandwidth, counted as 2 x 8 bytes per element like STREAM.
//
// Integrate counters: wall ms per frame split into allocate/update, blocks in the map and updated per frame, bytes per
// voxel (pool + hash over voxels), voxel updates/s (voxels of the visible blocks processed per second), effective
// bytes/s (each processed voxel is read and written: 16 bytes) and its fraction of the STREAM copy bandwidth
// measured in the same process; cpu_ms_all_threads is the CPU time of all threads per frame (divide by the
// core count for the wall time on an otherwise idle machine).
#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <tbb/parallel_for.h>

#include <chrono>
#include <cstring>
#include <memory>
#include <vector>

#include "bench/room_frames.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/deintegrate.h"
#include "fusion/integrate.h"

namespace {

constexpr int kFrames = hf::bench::kRoomFrames;

// CPU seconds used by the whole process (all threads): with other jobs on the machine, wall time per frame
// depends on the load, the CPU time spent on the frame much less.
double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}
constexpr int kWarmupFrames = 8;

using hf::bench::room_camera;
using hf::bench::room_frames;

// Parallel STREAM copy; returns bytes/s (2 x 8 bytes per element).
double stream_copy_bandwidth(int repetitions) {
  const size_t n = size_t(32) << 20;  // 32 Mi doubles = 256 MiB per array
  std::unique_ptr<double[]> a(new double[n]), b(new double[n]);
  tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
    for (size_t i = r.begin(); i != r.end(); ++i) a[i] = 0.0, b[i] = double(i);
  });
  double best_s = 1e30;
  for (int rep = 0; rep < repetitions; ++rep) {
    const auto t0 = std::chrono::steady_clock::now();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 16), [&](const tbb::blocked_range<size_t>& r) {
      std::memcpy(&a[r.begin()], &b[r.begin()], (r.end() - r.begin()) * sizeof(double));
    });
    best_s = std::min(best_s, std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    benchmark::DoNotOptimize(a[rep]);
  }
  return 2.0 * sizeof(double) * double(n) / best_s;
}

double copy_bandwidth() {
  static const double bw = stream_copy_bandwidth(5);
  return bw;
}

void BM_StreamCopy(benchmark::State& state) {
  double bw = 0;
  for (auto _ : state) bw = stream_copy_bandwidth(1);
  state.counters["GB/s"] = bw * 1e-9;
}
BENCHMARK(BM_StreamCopy)->Unit(benchmark::kMillisecond)->UseRealTime()->Iterations(5);

void BM_Integrate(benchmark::State& state) {
  const auto& frames = room_frames();
  hf::fusion::VolumeParams params;
  params.voxel_m = double(state.range(0)) * 1e-3;
  params.capacity_blocks = size_t(1) << 20;
  hf::fusion::VoxelBlockGrid grid(params);
  for (int i = 0; i < kWarmupFrames; ++i)
    hf::fusion::integrate(grid, frames[i].depth, frames[i].color, room_camera(), frames[i].T_world_camera);
  const double bandwidth = copy_bandwidth();

  int next = kWarmupFrames;
  double cpu_s = 0, alloc_ms = 0, update_ms = 0, visible = 0, updated = 0, allocated = 0;
  for (auto _ : state) {
    const auto& f = frames[next];
    next = next + 1 < kFrames ? next + 1 : kWarmupFrames;
    const double cpu0 = process_cpu_s();
    const hf::fusion::IntegrateStats s = hf::fusion::integrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
    cpu_s += process_cpu_s() - cpu0;
    alloc_ms += s.allocate_ms;
    update_ms += s.update_ms;
    visible += double(s.blocks_visible);
    updated += double(s.voxels_updated);
    allocated += double(s.blocks_allocated);
  }
  const double n = double(state.iterations());
  const double seconds = (alloc_ms + update_ms) * 1e-3;
  const double voxels_processed = visible * HF_VOXELS_PER_BLOCK;
  state.counters["alloc_ms"] = alloc_ms / n;
  state.counters["cpu_ms_all_threads"] = cpu_s * 1e3 / n;
  state.counters["update_ms"] = update_ms / n;
  state.counters["blocks_total"] = double(grid.block_count());
  state.counters["blocks_new/frame"] = allocated / n;
  state.counters["blocks_visible/frame"] = visible / n;
  state.counters["voxels_observed/frame"] = updated / n;
  state.counters["MiB"] = double(grid.memory_bytes()) / (1 << 20);
  state.counters["bytes/voxel"] = double(grid.memory_bytes()) / (double(grid.block_count()) * HF_VOXELS_PER_BLOCK);
  state.counters["Mvox_updates/s"] = voxels_processed / seconds * 1e-6;
  state.counters["update_GB/s"] = voxels_processed * 16.0 / (update_ms * 1e-3) * 1e-9;
  state.counters["copy_GB/s"] = bandwidth * 1e-9;
  state.counters["update_bw_fraction"] = voxels_processed * 16.0 / (update_ms * 1e-3) / bandwidth;
}
BENCHMARK(BM_Integrate)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

void BM_Deintegrate(benchmark::State& state) {
  const auto& frames = room_frames();
  hf::fusion::VolumeParams params;
  params.voxel_m = double(state.range(0)) * 1e-3;
  params.capacity_blocks = size_t(1) << 20;
  hf::fusion::VoxelBlockGrid grid(params);
  for (const auto& f : frames) hf::fusion::integrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
  int next = kWarmupFrames;
  double cpu_s = 0, find_ms = 0, update_ms = 0, release_ms = 0, updated = 0, visible = 0;
  for (auto _ : state) {
    const auto& f = frames[next];
    next = next + 1 < kFrames ? next + 1 : kWarmupFrames;
    const double cpu0 = process_cpu_s();
    const hf::fusion::DeintegrateStats s =
        hf::fusion::deintegrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
    cpu_s += process_cpu_s() - cpu0;
    state.PauseTiming();
    hf::fusion::integrate(grid, f.depth, f.color, room_camera(), f.T_world_camera);
    state.ResumeTiming();
    find_ms += s.find_ms;
    update_ms += s.update_ms;
    release_ms += s.release_ms;
    updated += double(s.voxels_updated);
    visible += double(s.blocks_visible);
  }
  const double n = double(state.iterations());
  state.counters["find_ms"] = find_ms / n;
  state.counters["update_ms"] = update_ms / n;
  state.counters["release_ms"] = release_ms / n;
  state.counters["cpu_ms_all_threads"] = cpu_s * 1e3 / n;
  state.counters["blocks_total"] = double(grid.block_count());
  state.counters["blocks_visible/frame"] = visible / n;
  state.counters["voxels_taken_out/frame"] = updated / n;
}
BENCHMARK(BM_Deintegrate)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime()->MinTime(2.0);

}  // namespace

BENCHMARK_MAIN();
