// LiDAR built-up areas (issue 22): points/s for reading LAS and gridding, ms per megacell for the morphology
// (components, heights, variant dilation, profile), on the synthetic settlements of lidar/synthetic_settlements.h.
// Results in bench/results/lidar.md.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <sstream>

#include "io/las.h"
#include "lidar/built_up_areas.h"
#include "lidar/synthetic_settlements.h"

namespace {

using namespace hf;
using namespace hf::lidar;

const SyntheticSettlements& scene(double cell_m) {
  static const SyntheticSettlements one = synthetic_settlements({cell_m, 1});
  return one;
}

void BM_LasRead(benchmark::State& state) {
  const auto& s = scene(1.0);
  LasHeader h;
  h.version_minor = 4, h.point_format = static_cast<int>(state.range(0));
  h.scale[0] = h.scale[1] = h.scale[2] = 0.001;
  const std::string bytes = format_las(h, s.points, "bench.las");
  std::vector<LasPoint> chunk;
  for (auto _ : state) {
    std::istringstream in(bytes);
    LasReader reader(in, bytes.size(), "bench.las");
    std::size_t n = 0;
    while (reader.read_chunk(chunk, 1 << 16)) n += chunk.size();
    benchmark::DoNotOptimize(n);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.points.size()));
  state.SetLabel("points/s; format " + std::to_string(h.point_format) + ", " + std::to_string(s.points.size()) + " points");
}
BENCHMARK(BM_LasRead)->Arg(1)->Arg(6)->Unit(benchmark::kMillisecond);

void BM_Gridding(benchmark::State& state) {
  const auto& s = scene(1.0);
  for (auto _ : state) {
    CellRaster r(s.grid);
    r.add(s.points);
    benchmark::DoNotOptimize(r.points);
  }
  state.SetItemsProcessed(state.iterations() * std::int64_t(s.points.size()));
  state.SetLabel("points/s");
}
BENCHMARK(BM_Gridding)->Unit(benchmark::kMillisecond);

void BM_Morphology(benchmark::State& state) {
  const double cell_m = 1.0;
  const auto& s = scene(cell_m);
  CellRaster r(s.grid);
  r.add(s.points);
  BuiltUpOptions o;
  o.cell_m = cell_m, o.t_s = 2.0, o.areas = s.areas;
  for (auto _ : state) benchmark::DoNotOptimize(classify_built_up(r, o).profile.stats[0].cells);
  const double megacells = double(s.grid.width) * s.grid.height / 1e6;
  state.counters["ms_per_megacell"] = benchmark::Counter(megacells / 1e3, benchmark::Counter::kIsIterationInvariantRate |
                                                                               benchmark::Counter::kInvert);
  state.SetLabel(std::to_string(s.grid.width) + " x " + std::to_string(s.grid.height) + " cells");
}
BENCHMARK(BM_Morphology)->Unit(benchmark::kMillisecond);

// The real AHN3 Delft crop from disk: LAS reading and gridding at 0.5 m together (skipped when absent).
void BM_DelftReadAndGrid(benchmark::State& state) {
  const std::string las = std::string(HF_SHARED_DIR) + "/data/lidar_ahn3_delft/ahn3_cropped_2.las";
  if (!std::filesystem::exists(las)) {
    state.SkipWithError("../shared/data/lidar_ahn3_delft absent");
    return;
  }
  const Grid grid = grid_of_files({las}, 0.5);
  std::uint64_t points = 0;
  for (auto _ : state) points = rasterise_files({las}, grid, {}).points;
  state.SetItemsProcessed(state.iterations() * std::int64_t(points));
  state.SetLabel("points/s; 208432 points, format 1");
}
BENCHMARK(BM_DelftReadAndGrid)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
