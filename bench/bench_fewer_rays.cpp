// Issue 19, the render for people with fewer rays: SSIM against the full render vs milliseconds, for
// fusion/sparse_render.h's reconstructions, on the fused synthetic room (20 frames at 1 cm, 640x480, the view of
// bench_surface's BM_Raycast) and on the map the SLAM pipeline fuses from the first 60 frames of TUM fr1/rpy
// (../shared/data; those rows are skipped when it is absent), seen from the last tracked pose.
//   BM_Full:          raycast() of every pixel (the reference; ssim 1 by definition)
//   BM_Halton:        render_masked on a Halton mask of range(1) % of the pixels, range(2) 0 push-pull, 1 mesh
//   BM_FocusDensity:  render_masked on a Halton mask following focus_density (full rate within 80 px of the
//                     centre, (80 / r)^2 outside, floor range(1) %), push-pull
//   BM_FocusContext:  render_focus_context, the centre 320x240 at full rate, the context at level range(1)
//   BM_Conus:         render_conus through a sampling map, the centre 160x160 at full rate, the context at
//                     range(1) % (linear rate)
// range(0) = 0 the synthetic room, 1 TUM fr1/rpy. Counters: ssim (core/ssim.h, on luma), rays_fraction, cast_ms,
// reconstruct_ms. Results in bench/results/fewer_rays_render.md.
//   build/release/bench/bench_fewer_rays --benchmark_min_time=0.5
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>
#include <memory>

#include "core/sample_patterns.h"
#include "core/ssim.h"
#include "datasets/synthetic_sequence.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/sparse_render.h"
#include "io/dataset.h"
#include "slam/pipeline.h"

namespace {

using namespace hf;
using namespace hf::fusion;

struct View {
  std::unique_ptr<VoxelBlockGrid> grid;            // the synthetic room's
  std::unique_ptr<slam::Pipeline> pipeline;        // or the TUM run's (its map)
  PinholeCamera camera;
  SE3 T_world_camera;
  ColorImage reference;
  const VoxelBlockGrid& map() const { return grid ? *grid : pipeline->map(); }
};

RaycastOptions render_options() {
  RaycastOptions o;
  o.shade = true;
  o.color = false;
  return o;
}

// nullptr when the scene's data is absent.
View* view(int scene) {
  static std::map<int, std::unique_ptr<View>> cache;
  auto it = cache.find(scene);
  if (it != cache.end()) return it->second.get();
  auto v = std::make_unique<View>();
  if (scene == 0) {
    datasets::SyntheticOptions o;
    o.preset = "room";
    o.frames = 100;
    datasets::SyntheticSequence seq(o);
    VolumeParams p;
    p.voxel_m = 0.01;
    p.capacity_blocks = 1 << 18;
    v->grid = std::make_unique<VoxelBlockGrid>(p);
    for (int i = 0; i < 80; i += 4) {
      const auto f = seq.frame(i);
      integrate(*v->grid, f.depth, f.color, seq.camera(), f.T_world_camera);
    }
    v->camera = seq.camera();
    v->T_world_camera = seq.T_world_camera(82);
  } else {
    const std::string path = std::string(HF_SHARED_DIR) + "/data/tum_fr1_rpy_first150";
    if (!std::filesystem::exists(path)) return cache.emplace(scene, nullptr).first->second.get();
    auto source = open_dataset(path);
    v->camera = source->camera();
    v->pipeline = std::make_unique<slam::Pipeline>(slam::PipelineConfig{}, v->camera);
    for (int i = 0; i < 60; ++i) {
      FrameRead r = source->next();
      if (r.status == FrameStatus::end) break;
      if (r.status != FrameStatus::ok) continue;
      const slam::FrameResult fr = v->pipeline->process(r.frame);
      if (fr.pose_valid) v->T_world_camera = fr.T_world_camera;
    }
  }
  v->reference = raycast(v->map(), v->camera, v->T_world_camera, render_options()).shaded;
  return cache.emplace(scene, std::move(v)).first->second.get();
}

void report(benchmark::State& state, const View& v, const SparseRender& r, double cast_ms, double reconstruct_ms) {
  const long n = long(v.camera.width) * v.camera.height;
  state.counters["ssim"] = ssim(r.shaded, v.reference).mssim;
  state.counters["rays_fraction"] = double(r.rays) / double(n);
  state.counters["cast_ms"] = cast_ms / double(state.iterations());
  state.counters["reconstruct_ms"] = reconstruct_ms / double(state.iterations());
}

void BM_Full(benchmark::State& state) {
  View* v = view(int(state.range(0)));
  if (!v) return state.SkipWithError("../shared/data/tum_fr1_rpy_first150 absent");
  RaycastResult out;
  for (auto _ : state) {
    raycast(v->map(), v->camera, v->T_world_camera, render_options(), &out);
    benchmark::DoNotOptimize(out.hit_count);
  }
  state.counters["ssim"] = ssim(out.shaded, v->reference).mssim;
  state.counters["rays_fraction"] = 1.0;
}
BENCHMARK(BM_Full)->ArgNames({"scene"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

void run_masked(benchmark::State& state, const View& v, const Image<std::uint8_t>& mask, Reconstruction method) {
  SparseRender r;
  double cast = 0, rec = 0;
  for (auto _ : state) {
    r = render_masked(v.map(), v.camera, v.T_world_camera, render_options(), mask, method);
    cast += r.cast_ms, rec += r.reconstruct_ms;
  }
  report(state, v, r, cast, rec);
}

Image<std::uint8_t> as_image(int w, int h, const std::vector<std::uint8_t>& m) {
  Image<std::uint8_t> img(w, h);
  img.pixels() = m;
  return img;
}

void BM_Halton(benchmark::State& state) {
  View* v = view(int(state.range(0)));
  if (!v) return state.SkipWithError("../shared/data/tum_fr1_rpy_first150 absent");
  const int w = v->camera.width, h = v->camera.height;
  const Image<std::uint8_t> mask = as_image(w, h, halton_mask(w, h, double(state.range(1)) / 100.0));
  run_masked(state, *v, mask, state.range(2) == 0 ? Reconstruction::push_pull : Reconstruction::mesh);
}
BENCHMARK(BM_Halton)
    ->ArgNames({"scene", "percent", "mesh"})
    ->ArgsProduct({{0, 1}, {10, 30, 50}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_FocusDensity(benchmark::State& state) {
  View* v = view(int(state.range(0)));
  if (!v) return state.SkipWithError("../shared/data/tum_fr1_rpy_first150 absent");
  const int w = v->camera.width, h = v->camera.height;
  const float floor = float(state.range(1)) / 100.0f;
  const Image<float> density = focus_density(w, h, 0.5f * (w - 1), 0.5f * (h - 1), 80.0f, floor);
  run_masked(state, *v, as_image(w, h, halton_mask(density)), Reconstruction::push_pull);
}
BENCHMARK(BM_FocusDensity)
    ->ArgNames({"scene", "floor_percent"})
    ->ArgsProduct({{0, 1}, {5, 20}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_FocusContext(benchmark::State& state) {
  View* v = view(int(state.range(0)));
  if (!v) return state.SkipWithError("../shared/data/tum_fr1_rpy_first150 absent");
  const int w = v->camera.width, h = v->camera.height;
  const PixelRect roi{w / 4, h / 4, 3 * w / 4, 3 * h / 4};
  SparseRender r;
  double cast = 0, rec = 0;
  for (auto _ : state) {
    r = render_focus_context(v->map(), v->camera, v->T_world_camera, render_options(), roi, int(state.range(1)));
    cast += r.cast_ms, rec += r.reconstruct_ms;
  }
  report(state, *v, r, cast, rec);
}
BENCHMARK(BM_FocusContext)
    ->ArgNames({"scene", "context_level"})
    ->ArgsProduct({{0, 1}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// Popescu's CoNUS view: 16x12 cells, the centre 4x4 cells at full rate, the others at range(1) / 100.
void BM_Conus(benchmark::State& state) {
  View* v = view(int(state.range(0)));
  if (!v) return state.SkipWithError("../shared/data/tum_fr1_rpy_first150 absent");
  std::vector<float> rates(16 * 12, float(state.range(1)) / 100.0f);
  for (int j = 4; j < 8; ++j)
    for (int i = 6; i < 10; ++i) rates[size_t(j) * 16 + i] = 1.0f;
  const SamplingMap map = SamplingMap::from_region_rates(v->camera.width, v->camera.height, 16, 12, rates);
  SparseRender r;
  double cast = 0, rec = 0;
  for (auto _ : state) {
    r = render_conus(v->map(), v->camera, v->T_world_camera, render_options(), map);
    cast += r.cast_ms, rec += r.reconstruct_ms;
  }
  report(state, *v, r, cast, rec);
}
BENCHMARK(BM_Conus)
    ->ArgNames({"scene", "context_rate_percent"})
    ->ArgsProduct({{0, 1}, {50, 25}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
