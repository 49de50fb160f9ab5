// Per-frame image preprocessing at 640x480 (the "ros" camera): bilateral filter, pyramids, vertex + normal maps.
// The input is a noisy analytic scene (tilted plane with a sphere in front), so timings include realistic
// range-weight and edge behaviour.
#include <benchmark/benchmark.h>

#include <cmath>
#include <random>

#include "core/camera.h"
#include "core/filters.h"
#include "core/normals.h"
#include "core/pyramid.h"

namespace {

hf::DepthImage make_depth(const hf::PinholeCamera& cam) {
  hf::DepthImage d(cam.width, cam.height);
  std::mt19937 rng(1);
  std::normal_distribution<float> noise(0.0f, 0.004f);
  const double nx = 0.2, ny = -0.3, nz = 1.0, dist = 2.5 / std::sqrt(nx * nx + ny * ny + nz * nz);
  const double scx = 0.1, scy = 0.0, scz = 1.5, r = 0.4;
  for (int y = 0; y < cam.height; ++y) {
    for (int x = 0; x < cam.width; ++x) {
      const double rx = (x - cam.cx) / cam.fx, ry = (y - cam.cy) / cam.fy;
      double depth = dist * std::sqrt(nx * nx + ny * ny + nz * nz) / (nx * rx + ny * ry + nz);
      const double a = rx * rx + ry * ry + 1.0, b = rx * scx + ry * scy + scz;
      const double disc = b * b - a * (scx * scx + scy * scy + scz * scz - r * r);
      if (disc >= 0.0) depth = std::min(depth, (b - std::sqrt(disc)) / a);
      d(x, y) = (x * 7 + y * 13) % 97 == 0 ? 0.0f : float(depth) + noise(rng);  // ~1% holes
    }
  }
  return d;
}

const hf::PinholeCamera& camera() {
  static const hf::PinholeCamera cam = hf::PinholeCamera::preset("ros");
  return cam;
}

const hf::DepthImage& depth() {
  static const hf::DepthImage d = make_depth(camera());
  return d;
}

void BM_BilateralFilter640x480(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(hf::bilateral_filter_depth(depth()).data());
  state.SetItemsProcessed(state.iterations() * int64_t(depth().size()));
}
BENCHMARK(BM_BilateralFilter640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_DepthPyramid3Levels(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(hf::build_depth_pyramid(depth(), 3).back().data());
}
BENCHMARK(BM_DepthPyramid3Levels)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_GaussianPyramid3Levels(benchmark::State& state) {
  hf::Image<float> intensity(camera().width, camera().height);
  for (int y = 0; y < intensity.height(); ++y)
    for (int x = 0; x < intensity.width(); ++x) intensity(x, y) = 0.5f + 0.4f * std::sin(0.05f * x) * std::cos(0.07f * y);
  for (auto _ : state) benchmark::DoNotOptimize(hf::build_gaussian_pyramid(intensity, 3).back().data());
}
BENCHMARK(BM_GaussianPyramid3Levels)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_VertexNormalMaps640x480(benchmark::State& state) {
  for (auto _ : state) {
    const hf::VertexMap v = hf::compute_vertex_map(depth(), camera());
    benchmark::DoNotOptimize(hf::compute_normal_map(v).data());
  }
  state.SetItemsProcessed(state.iterations() * int64_t(depth().size()));
}
BENCHMARK(BM_VertexNormalMaps640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_ImageGradients640x480(benchmark::State& state) {
  const hf::Image<float> img(camera().width, camera().height, 0.5f);
  for (auto _ : state) benchmark::DoNotOptimize(hf::image_gradients(img).dx.data());
}
BENCHMARK(BM_ImageGradients640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

// The whole per-frame preprocessing a tracker runs: filter, 3-level depth pyramid, vertex + normal maps per level.
void BM_FramePreprocessing640x480(benchmark::State& state) {
  for (auto _ : state) {
    const auto pyramid = hf::build_depth_pyramid(hf::bilateral_filter_depth(depth()), 3);
    for (size_t l = 0; l < pyramid.size(); ++l) {
      const hf::VertexMap v = hf::compute_vertex_map(pyramid[l], camera().scaled(int(l)));
      benchmark::DoNotOptimize(hf::compute_normal_map(v).data());
    }
  }
}
BENCHMARK(BM_FramePreprocessing640x480)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
