// Head features (issue 21): ms per vertex evaluation (discrete H and K, MLS cubic fit, cotangent Laplace-Beltrami)
// on each mesh of ../shared/data/head_meshes, as vertices/s; the topology is built once outside the timing.
// Results in bench/results/head.md. Meshes that are absent are skipped with a message.
#include <benchmark/benchmark.h>

#include <filesystem>
#include <map>

#include "head/discrete_curvature.h"
#include "head/laplace_beltrami.h"
#include "io/mesh_file.h"
#include "head/mls_curvature.h"

namespace {

using namespace hf;
using namespace hf::head;

const char* const kMeshes[] = {"max_planck_decimated.obj", "libigl_face_head.obj", "nefertiti.obj", "igea_tristrips.ply"};

struct Loaded {
  TriangleMesh mesh;
  MeshTopology topology;
};

// The mesh and its topology, loaded once per process; null when ../shared is absent.
const Loaded* mesh_of(int index) {
  static std::map<int, Loaded> cache;
  if (auto it = cache.find(index); it != cache.end()) return &it->second;
  const std::string path = std::string(HF_SHARED_DIR) + "/data/head_meshes/" + kMeshes[index];
  if (!std::filesystem::exists(path)) return nullptr;
  Loaded l;
  l.mesh = read_mesh_file(path);
  l.topology = build_topology(l.mesh);
  return &cache.emplace(index, std::move(l)).first->second;
}

template <class Evaluate>
void run(benchmark::State& state, Evaluate evaluate) {
  const Loaded* l = mesh_of(static_cast<int>(state.range(0)));
  if (!l) {
    state.SkipWithError("../shared/data/head_meshes is absent");
    return;
  }
  for (auto _ : state) benchmark::DoNotOptimize(evaluate(*l));
  state.SetItemsProcessed(state.iterations() * std::int64_t(l->mesh.vertices.size()));
  state.SetLabel(std::string(kMeshes[state.range(0)]) + ", " + std::to_string(l->mesh.vertices.size()) + " vertices; items = vertices");
}

void BM_Discrete(benchmark::State& state) {
  run(state, [](const Loaded& l) { return discrete_curvature(l.mesh, l.topology); });
}
void BM_Mls(benchmark::State& state) {
  run(state, [](const Loaded& l) { return mls_curvature(l.mesh, l.topology); });  // the default 3-ring cubic fit
}
void BM_Laplace(benchmark::State& state) {
  run(state, [](const Loaded& l) { return laplace_beltrami(l.mesh, l.topology); });
}
BENCHMARK(BM_Discrete)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Mls)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Laplace)->DenseRange(0, 3)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
