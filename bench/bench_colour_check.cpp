// The colour check (slam/colour_check.h): ms per estimate_colour_alignment() on one frame of the synthetic room and
// of its `unregistered` twin, on the 320x240 level the pipeline tracks (and checks) a 640x480 frame at. Counter:
// the scale read (1 for registered colour, ~0.9 for the unregistered preset's 525/585 focal length). The pipeline
// runs one estimate every ColourCheckOptions::frame_step-th frame until the window decides (10 estimates).
// Results: bench/results/tracking.md ("Colour registration").
#include <benchmark/benchmark.h>

#include <string>

#include "datasets/synthetic_sequence.h"
#include "registration/frame_pyramid.h"
#include "slam/colour_check.h"

namespace {

hf::FramePyramidLevel level_of(const std::string& preset) {
  hf::datasets::SyntheticOptions o;
  o.preset = preset;
  o.frames = 1;
  const hf::datasets::SyntheticSequence seq(o);
  const hf::datasets::SyntheticFrame f = seq.frame(0);
  hf::FramePyramidOptions po;
  po.first_level = 1;
  return hf::build_frame_pyramid(f.depth, &f.color, seq.camera(), po).levels[0];
}

void BM_ColourAlignment(benchmark::State& state, const std::string& preset) {
  const hf::FramePyramidLevel level = level_of(preset);
  const hf::slam::ColourCheckOptions options;
  hf::slam::ColourAlignment a;
  for (auto _ : state) {
    a = hf::slam::estimate_colour_alignment(level, options);
    benchmark::DoNotOptimize(a);
  }
  state.counters["scale"] = a.scale;
  state.counters["valid"] = a.valid ? 1 : 0;
  state.counters["depth_edges"] = double(a.depth_edges);
}
BENCHMARK_CAPTURE(BM_ColourAlignment, room, std::string("room"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_ColourAlignment, unregistered, std::string("unregistered"))->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
