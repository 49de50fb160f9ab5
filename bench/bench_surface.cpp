// Raycast and marching-cubes meshing on the room preset (issue 3): a 640x480 raycast at 1 cm and 5 mm voxels
// after fusing 20 noisy frames, the SLAM pipeline's raycast at the pose just integrated with and without
// RaycastOptions::depth_hint (640x480 and 320x240; with the hint also with the pipeline's other tracking options),
// the floor under those raycasts (BM_RaycastFloor: one sample and normal per hit pixel, no search), and meshing
// the whole map. Results in bench/results/fusion.md.
// cpu_ms_all_threads is the CPU time of all threads per iteration: with other jobs on the 2 cores it depends on
// the load far less than the wall time does.
//   build/release/bench/bench_surface
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <map>
#include <memory>

#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "fusion/mesh.h"
#include "fusion/raycast.h"
#include "slam/pipeline.h"

namespace {

using namespace hf;
using namespace hf::fusion;

double process_cpu_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

struct Scene {
  std::unique_ptr<datasets::SyntheticSequence> seq;
  std::unique_ptr<VoxelBlockGrid> grid;
};

// One fused room per voxel size and camera scale (built once; frames 0, 4, ..., 76 of the room sequence with the
// 640x480 "ros" camera, or that camera scaled(scale): 1 = 320x240).
Scene& room(double voxel_m, int scale = 0) {
  static std::map<std::pair<double, int>, Scene> cache;
  Scene& s = cache[{voxel_m, scale}];
  if (!s.grid) {
    datasets::SyntheticOptions o;
    o.preset = "room";
    o.frames = 100;
    o.camera = PinholeCamera::preset("ros").scaled(scale);
    s.seq = std::make_unique<datasets::SyntheticSequence>(o);
    VolumeParams p;
    p.voxel_m = voxel_m;
    p.capacity_blocks = 1 << 18;
    s.grid = std::make_unique<VoxelBlockGrid>(p);
    for (int i = 0; i < 80; i += 4) {
      const auto f = s.seq->frame(i);
      integrate(*s.grid, f.depth, f.color, s.seq->camera(), f.T_world_camera);
    }
  }
  return s;
}

void BM_Raycast(benchmark::State& state) {
  const double voxel_m = state.range(0) / 1000.0;
  Scene& s = room(voxel_m);
  const SE3 T = s.seq->T_world_camera(82);  // a pose between the fused ones
  RaycastResult out;
  RaycastOptions opts;
  opts.shade = state.range(1) != 0;
  const double cpu0 = process_cpu_s();
  for (auto _ : state) {
    raycast(*s.grid, s.seq->camera(), T, opts, &out);
    benchmark::DoNotOptimize(out.hit_count);
  }
  state.counters["cpu_ms_all_threads"] = (process_cpu_s() - cpu0) * 1e3 / double(state.iterations());
  state.counters["hits"] = out.hit_count;
  state.counters["blocks"] = double(s.grid->block_count());
}
BENCHMARK(BM_Raycast)->Args({10, 0})->Args({10, 1})->Args({5, 0})->Unit(benchmark::kMillisecond)->UseRealTime();

// The SLAM pipeline's case: raycast at the pose of the frame just integrated (frame 76, the last one fused), with
// that frame's depth as RaycastOptions::depth_hint (range(2) = 1) or without (0), no shading. range(1) is the
// camera scale: 0 = 640x480, 1 = 320x240. range(3) = 1 takes the SLAM pipeline's tracking options
// (slam::PipelineConfig::raycast: no colour, crossing refined to 0.05 voxel); 0 keeps RaycastOptions' defaults.
void BM_RaycastAtIntegratedPose(benchmark::State& state) {
  const double voxel_m = state.range(0) / 1000.0;
  Scene& s = room(voxel_m, int(state.range(1)));
  const datasets::SyntheticFrame f = s.seq->frame(76);
  RaycastResult out;
  RaycastOptions opts = state.range(3) != 0 ? slam::PipelineConfig().raycast : RaycastOptions{};
  opts.shade = false;
  if (state.range(2) != 0) opts.depth_hint = &f.depth;
  const double cpu0 = process_cpu_s();
  for (auto _ : state) {
    raycast(*s.grid, s.seq->camera(), f.T_world_camera, opts, &out);
    benchmark::DoNotOptimize(out.hit_count);
  }
  state.counters["cpu_ms_all_threads"] = (process_cpu_s() - cpu0) * 1e3 / double(state.iterations());
  state.counters["hits"] = out.hit_count;
  state.counters["blocks"] = double(s.grid->block_count());
}
BENCHMARK(BM_RaycastAtIntegratedPose)
    ->ArgNames({"voxel_mm", "scale", "hint", "slam"})
    ->Args({10, 0, 0, 0})
    ->Args({10, 0, 1, 0})
    ->Args({10, 0, 1, 1})
    ->Args({10, 1, 0, 0})
    ->Args({10, 1, 1, 0})
    ->Args({10, 1, 1, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The floor under a raycast of this volume: at every pixel where the 640x480 raycast at the integrated pose (hint,
// pipeline options) hit, one trilinear SDF sample at the hit point (VolumeSampler::sdf: what a ray that lands on
// the surface with its first sample still pays) and, with range(1) = 1, its normal (VolumeSampler::normal), over
// the same 16 x 16-pixel tiles on all cores, with the look-up table prebuilt. No march, no range image, no output
// images: what remains of raycast() when every ray's search costs nothing. range(0) = voxel mm.
void BM_RaycastFloor(benchmark::State& state) {
  const double voxel_m = state.range(0) / 1000.0;
  const bool with_normal = state.range(1) != 0;
  Scene& s = room(voxel_m);
  const datasets::SyntheticFrame f = s.seq->frame(76);
  RaycastOptions opts = slam::PipelineConfig().raycast;
  opts.shade = false;
  opts.depth_hint = &f.depth;
  const RaycastResult hits = raycast(*s.grid, s.seq->camera(), f.T_world_camera, opts);
  const int W = s.seq->camera().width, H = s.seq->camera().height;
  std::vector<Eigen::Vector3f> p_vox(size_t(W) * H, Eigen::Vector3f::Constant(std::nanf("")));
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const hf_float4 v = hits.vertices(x, y);
      if (v.w != 1.0f) continue;
      p_vox[size_t(y) * W + x] =
          s.grid->voxel_coords(f.T_world_camera * Eigen::Vector3d(v.x, v.y, v.z)).cast<float>();
    }
  constexpr int kWork = 16;
  const int WX = (W + kWork - 1) / kWork, WY = (H + kWork - 1) / kWork;
  std::vector<int> tile_normals(size_t(WX) * WY);
  const double cpu0 = process_cpu_s();
  for (auto _ : state) {
    tbb::parallel_for(tbb::blocked_range<int>(0, WX * WY), [&](const tbb::blocked_range<int>& work) {
      VolumeSampler sampler(*s.grid, opts.min_weight, opts.skip_blocks);
      for (int wi = work.begin(); wi != work.end(); ++wi) {
        const int x0 = (wi % WX) * kWork, y0 = (wi / WX) * kWork;
        int n_ok = 0;
        for (int y = y0; y < std::min(y0 + kWork, H); ++y)
          for (int x = x0; x < std::min(x0 + kWork, W); ++x) {
            const Eigen::Vector3f& p = p_vox[size_t(y) * W + x];
            float sdf = 0.0f;
            Eigen::Vector3f n;
            if (!std::isnan(p.x()) && sampler.sdf(p, &sdf) && (!with_normal || sampler.normal(p, &n))) ++n_ok;
          }
        tile_normals[size_t(wi)] = n_ok;
      }
    });
    benchmark::DoNotOptimize(tile_normals.data());
  }
  int normals = 0;  // pixels whose sample (and normal) was valid
  for (int n : tile_normals) normals += n;
  state.counters["cpu_ms_all_threads"] = (process_cpu_s() - cpu0) * 1e3 / double(state.iterations());
  state.counters["hits"] = hits.hit_count;
  state.counters["samples_ok"] = normals;
}
BENCHMARK(BM_RaycastFloor)->ArgNames({"voxel_mm", "normal"})->Args({10, 0})->Args({10, 1})->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Mesh(benchmark::State& state) {
  const double voxel_m = state.range(0) / 1000.0;
  Scene& s = room(voxel_m);
  size_t tris = 0, verts = 0;
  const double cpu0 = process_cpu_s();
  for (auto _ : state) {
    const TriangleMesh m = extract_mesh(*s.grid);
    tris = m.triangles.size();
    verts = m.vertices.size();
    benchmark::DoNotOptimize(tris);
  }
  state.counters["cpu_ms_all_threads"] = (process_cpu_s() - cpu0) * 1e3 / double(state.iterations());
  state.counters["triangles"] = double(tris);
  state.counters["vertices"] = double(verts);
  state.counters["blocks"] = double(s.grid->block_count());
}
BENCHMARK(BM_Mesh)->Arg(10)->Arg(5)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
