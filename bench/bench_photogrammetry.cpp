// Photogrammetric modelling (issue 23): ms per triangulated vertex (2, 3, 10 shots), per RANSAC segmentation of the
// Sceaux sparse cloud (12,683 points), per cloud fit of a sketched facade, per texture of the synthetic box
// building's front facade; results in bench/results/photogrammetry.md.
//   build/release/bench/bench_photogrammetry
#include <benchmark/benchmark.h>

#include <filesystem>

#include "photogrammetry/dlt_triangulation.h"
#include "photogrammetry/scene_readers.h"
#include "photogrammetry/single_shot_sketching.h"
#include "photogrammetry/texture.h"
#include "tests/photogrammetry/box_building.h"

namespace pg = hf::photogrammetry;
using pg::testing::BoxBuilding;

static void BM_TriangulateVertex(benchmark::State& state) {
  const int n = int(state.range(0));
  std::vector<pg::DltObservation> obs;
  const Eigen::Vector3d X(5, 0.3, 3);
  for (int k = 0; k < n; ++k) {
    const double a = -0.6 + 1.2 * k / std::max(1, n - 1);
    const pg::Shot s = pg::testing::look_at("s", {5 + 15 * std::sin(a), -15 * std::cos(a), 2}, {5, 0, 3});
    obs.push_back(pg::observation(s, *s.project(X)));
  }
  for (auto _ : state) benchmark::DoNotOptimize(pg::triangulate_dlt(obs));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_TriangulateVertex)->Arg(2)->Arg(3)->Arg(10)->Unit(benchmark::kMicrosecond);

static void BM_RansacSceaux(benchmark::State& state) {
  const std::string dir = std::string(HF_SHARED_DIR) + "/data/photogrammetry_sceaux_castle";
  if (!std::filesystem::exists(dir)) {
    state.SkipWithError("../shared absent");
    return;
  }
  const pg::Network n = pg::read_network(dir);
  pg::RansacPlaneOptions o;
  o.max_planes = int(state.range(0));
  size_t planes = 0;
  for (auto _ : state) planes = pg::segment_planes_ransac(n.cloud.positions, o).size();
  state.counters["planes"] = double(planes);
  state.counters["points"] = double(n.cloud.size());
}
BENCHMARK(BM_RansacSceaux)->Arg(4)->Arg(20)->Unit(benchmark::kMillisecond);

static void BM_FitSegmentsBoxFacade(benchmark::State& state) {
  const BoxBuilding b;
  const pg::Cloud cloud = b.cloud(0.2, 0.01, 1);
  pg::RansacPlaneOptions o;
  o.distance_threshold = 0.03;
  const std::vector<pg::PlaneSegment> segments = pg::segment_planes_ransac(cloud.positions, o);
  const pg::Shot shot = BoxBuilding::shots()[1];
  const pg::Polygon2d outline = b.project(shot, b.front_corners());
  for (auto _ : state) benchmark::DoNotOptimize(pg::fit_segments(shot, 1, outline, cloud, segments));
  state.counters["segments"] = double(segments.size());
}
BENCHMARK(BM_FitSegmentsBoxFacade)->Unit(benchmark::kMillisecond);

static void BM_TextureBoxFacade(benchmark::State& state) {
  const BoxBuilding b;
  pg::Network n;
  n.shots = BoxBuilding::shots();
  std::vector<hf::ColorImage> images;
  for (const pg::Shot& s : n.shots) images.push_back(b.render(s));
  std::vector<const hf::ColorImage*> ptrs;
  for (const auto& i : images) ptrs.push_back(&i);
  pg::TextureOptions o;
  o.texel_size = 10.0 / double(state.range(0));
  size_t texels = 0;
  for (auto _ : state) {
    const auto t = pg::build_texture(b.front_corners(), {0, -1, 0, 0}, n, ptrs, o);
    texels = t->image.size();
  }
  state.counters["texels"] = double(texels);
}
BENCHMARK(BM_TextureBoxFacade)->Arg(200)->Arg(1000)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
