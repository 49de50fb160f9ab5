// Registration benchmark: ms per registration at 640x480 for each method x backend, and the error against ground
// truth on synthetic pairs (datasets::SyntheticSequence "room") and on consecutive frames of the real TUM
// sequences in ../shared/data, with PCL's GICP and NDT on the same pairs as reference rows.
//
//   build/release/bench/bench_registration                      # Google Benchmark timings (synthetic pair)
//   build/release/bench/bench_registration --accuracy [--max-pairs N] [--pcl-pairs N] [--first-level L]
//                                                               # the accuracy tables (markdown on stdout); L = 1
//                                                               # builds the pyramids from 320x240 as the SLAM
//                                                               # pipeline's tracking_level 1 does
//   build/release/bench/bench_registration --lambda-sweep [--max-pairs N]
//                                                               # combined's rgb_weight on the TUM pairs
//
// Methods and backends come from the registries (registration_names(), backend_names()); a backend that cannot
// be created here (e.g. opencl without a platform) is reported and skipped. Results: bench/results/registration.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "bench/pcl_reference.h"
#include "core/error.h"
#include "datasets/synthetic_sequence.h"
#include "io/dataset.h"
#include "registration/frame_pyramid.h"
#include "registration/cpu_backend.h"
#include "registration/gauss_newton.h"
#include "registration/ndt/ndt_options.h"
#include "registration/registration.h"
#ifdef HF_BENCH_HAVE_OPENCL
#include "registration/opencl/opencl_backend.h"
#endif

namespace hf {
namespace {

#ifndef HF_SHARED_DIR
#define HF_SHARED_DIR "../shared"
#endif

struct Pair {
  FramePyramid cur, ref;
  SE3 T_ref_cur_true;
  std::vector<Eigen::Vector3f> cur_points, ref_points;  // level-0 vertices, for PCL
};

struct PairSet {
  std::string name;
  std::vector<Pair> pairs;
};

double elapsed_ms(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

std::vector<Eigen::Vector3f> points_of(const VertexMap& v) {
  std::vector<Eigen::Vector3f> out;
  out.reserve(v.size());
  for (const hf_float4& p : v.pixels()) {
    if (p.w != 0.0f) out.emplace_back(p.x, p.y, p.z);
  }
  return out;
}

Pair make_pair_of(const DepthImage& d_ref, const ColorImage& c_ref, const SE3& T_w_ref, const DepthImage& d_cur,
                  const ColorImage& c_cur, const SE3& T_w_cur, const PinholeCamera& camera, int first_level = 0) {
  Pair p;
  FramePyramidOptions options;
  options.first_level = first_level;
  p.ref = build_frame_pyramid(d_ref, &c_ref, camera, options);
  p.cur = build_frame_pyramid(d_cur, &c_cur, camera, options);
  p.T_ref_cur_true = T_w_ref.inverse() * T_w_cur;
  p.ref_points = points_of(p.ref.levels[0].vertices);
  p.cur_points = points_of(p.cur.levels[0].vertices);
  return p;
}

// Consecutive frames k, k+1 of the synthetic room (with sensor noise), 640x480.
PairSet synthetic_pairs(int count, int first_level = 0) {
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = count + 1;
  datasets::SyntheticSequence seq(options);
  PairSet set{"synthetic room (noisy, consecutive frames)", {}};
  datasets::SyntheticFrame prev = seq.frame(0);
  for (int i = 1; i <= count; ++i) {
    datasets::SyntheticFrame next = seq.frame(i);
    set.pairs.push_back(make_pair_of(prev.depth, prev.color, prev.T_world_camera, next.depth, next.color,
                                     next.T_world_camera, seq.camera(), first_level));
    prev = std::move(next);
  }
  return set;
}

// Consecutive frames of a TUM folder with ground truth for both.
PairSet tum_pairs(const std::string& folder, int max_pairs, int first_level = 0) {
  DatasetOptions options;
  options.prefetch_frames = 0;
  std::unique_ptr<FrameSource> source = open_dataset(folder, options);
  PairSet set{"TUM " + std::filesystem::path(folder).filename().string() + " (consecutive frames)", {}};
  std::optional<RgbdFrame> prev;
  while (int(set.pairs.size()) < max_pairs) {
    FrameRead read = source->next();
    if (read.status == FrameStatus::end) break;
    if (read.status != FrameStatus::ok || !read.frame.T_world_camera_gt) {
      prev.reset();
      continue;
    }
    if (prev) {
      set.pairs.push_back(make_pair_of(prev->depth, prev->color, *prev->T_world_camera_gt, read.frame.depth,
                                       read.frame.color, *read.frame.T_world_camera_gt, source->camera(),
                                       first_level));
    }
    prev = std::move(read.frame);
  }
  return set;
}

struct Errors {
  double t_mm = 0.0, r_deg = 0.0;
};

Errors error_of(const SE3& T_est, const SE3& T_true) {
  const SE3 E = T_true.inverse() * T_est;
  const Eigen::AngleAxisd aa(E.rotation());
  return {E.translation().norm() * 1e3, std::fabs(aa.angle()) * 180.0 / M_PI};
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / double(v.size());
}
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

struct Row {
  std::string method, backend;
  std::vector<double> ms, t_mm, r_deg, iterations;
  std::map<std::string, int> statuses;
  std::vector<double> eigen_ratio;  // smallest / largest balanced eigenvalue of each result
};

void print_row(const Row& r) {
  std::string st;
  for (const auto& [name, n] : r.statuses) st += (st.empty() ? "" : ", ") + name + " " + std::to_string(n);
  std::printf("| %s | %s | %zu | %.1f | %.1f | %.2f / %.2f | %.3f / %.3f | %s |\n", r.method.c_str(),
              r.backend.c_str(), r.ms.size(), mean(r.ms), mean(r.iterations), mean(r.t_mm), median(r.t_mm),
              mean(r.r_deg), median(r.r_deg), st.c_str());
}

std::vector<std::string> usable_backends() {
  std::vector<std::string> out;
  for (const std::string& b : backend_names()) {
    try {
      make_backend(b);
      out.push_back(b);
    } catch (const Error& e) {
      std::printf("(backend %s skipped: %s)\n", b.c_str(), e.what());
    }
  }
  return out;
}

void accuracy_table(const PairSet& set, int pcl_pairs) {
  std::printf("\n### %s: %zu pairs\n\n", set.name.c_str(), set.pairs.size());
  std::printf("| method | backend | pairs | ms / registration | iterations | trans. error mean / median (mm) | "
              "rot. error mean / median (deg) | status |\n|---|---|---|---|---|---|---|---|\n");
  {
    Row identity{"(identity: no motion estimated)", "-", {}, {}, {}, {}, {}, {}};
    for (const Pair& p : set.pairs) {
      const Errors e = error_of(SE3(), p.T_ref_cur_true);
      identity.t_mm.push_back(e.t_mm);
      identity.r_deg.push_back(e.r_deg);
      identity.ms.push_back(0.0);
    }
    print_row(identity);
  }
  for (const std::string& method : registration_names()) {
    for (const std::string& backend : usable_backends()) {
      std::unique_ptr<Registration> reg = make_registration(method, backend);
      Row row{method, backend, {}, {}, {}, {}, {}, {}};
      for (const Pair& p : set.pairs) {
        const auto start = std::chrono::steady_clock::now();
        const RegistrationResult res = reg->align(p.cur, p.ref, SE3());
        row.ms.push_back(elapsed_ms(start));
        const Errors e = error_of(res.T_ref_cur, p.T_ref_cur_true);
        row.t_mm.push_back(e.t_mm);
        row.r_deg.push_back(e.r_deg);
        row.iterations.push_back(
            double(std::accumulate(res.iterations_per_level.begin(), res.iterations_per_level.end(), 0)));
        ++row.statuses[to_string(res.status)];
      }
      print_row(row);
      std::fflush(stdout);
    }
  }
  const int n_pcl = std::min<int>(pcl_pairs, int(set.pairs.size()));
  for (const char* method : {"gicp", "ndt"}) {
    Row row{std::string("PCL ") + (std::strcmp(method, "gicp") == 0 ? "GICP" : "NDT") + " (reference)",
            "PCL, 1 thread", {}, {}, {}, {}, {}, {}};
    int points = 0;
    for (int i = 0; i < n_pcl; ++i) {
      const Pair& p = set.pairs[size_t(i)];
      const bench::PclAlignResult res = bench::pcl_align(method, p.cur_points, p.ref_points, 0.04f, 0.2f);
      row.ms.push_back(res.ms);
      const Errors e = error_of(SE3::from_matrix(res.T_target_source), p.T_ref_cur_true);
      row.t_mm.push_back(e.t_mm);
      row.r_deg.push_back(e.r_deg);
      row.iterations.push_back(0.0);
      ++row.statuses[res.converged ? "converged" : "not converged"];
      points += res.source_points;
    }
    if (n_pcl > 0) {
      row.backend += ", ~" + std::to_string(points / n_pcl) + " pts";
      print_row(row);
      std::fflush(stdout);
    }
  }
}

int run_accuracy(int max_pairs, int pcl_pairs, int first_level) {
  std::printf("## Accuracy and time per registration (640x480 frames, pyramids from level %d = %dx%d, initial "
              "guess = identity, frame to frame)\n",
              first_level, 640 >> first_level, 480 >> first_level);
  std::printf("\nms / registration: align() only (pyramids built beforehand), mean over the pairs. iterations: "
              "sum over the pyramid levels, mean. Errors: |t| and angle of T_true^-1 T_est.\n");
  accuracy_table(synthetic_pairs(std::min(max_pairs, 20), first_level), pcl_pairs);
  for (const char* name : {"tum_fr1_desk_9frames", "tum_fr1_rpy_first150"}) {
    const std::string folder = std::string(HF_SHARED_DIR) + "/data/" + name;
    if (!std::filesystem::exists(folder)) {
      std::printf("\n(%s missing: skipped)\n", folder.c_str());
      continue;
    }
    accuracy_table(tum_pairs(folder, max_pairs, first_level), pcl_pairs);
  }
  return 0;
}

// ---- Choice of lambda (rgb_weight of combined, eq. 48) on the real TUM sequences -------------------------------

// For every consecutive pair with ground truth of each TUM folder (frames streamed, one pyramid pair in memory),
// combined with each lambda (and icp as the lambda = 0 reference): error statistics per lambda.
int run_lambda_sweep(int max_pairs) {
  const std::vector<float> lambdas = {0.0f, 0.01f, 0.02f, 0.05f, 0.1f, 0.2f, 0.5f, 1.0f};
  std::printf("## lambda sweep: combined (cpu) frame to frame, identity guess, 640x480\n");
  for (const char* name : {"tum_fr1_rpy_first150", "tum_fr1_desk_9frames"}) {
    const std::string folder = std::string(HF_SHARED_DIR) + "/data/" + name;
    if (!std::filesystem::exists(folder)) {
      std::printf("\n(%s missing: skipped)\n", folder.c_str());
      continue;
    }
    std::vector<std::unique_ptr<Registration>> regs;
    std::vector<Row> rows;
    for (const float lambda : lambdas) {
      RegistrationOptions o = default_registration_options("combined");
      o.set("rgb_weight", double(lambda));
      regs.push_back(make_registration("combined", o, make_backend("cpu")));
      char label[32];
      std::snprintf(label, sizeof(label), "%g", double(lambda));
      rows.push_back(Row{label, "cpu", {}, {}, {}, {}, {}, {}});
    }
    DatasetOptions options;
    options.prefetch_frames = 0;
    std::unique_ptr<FrameSource> source = open_dataset(folder, options);
    std::optional<FramePyramid> prev;
    SE3 T_w_prev;
    int pairs = 0;
    while (pairs < max_pairs) {
      FrameRead read = source->next();
      if (read.status == FrameStatus::end) break;
      if (read.status != FrameStatus::ok || !read.frame.T_world_camera_gt) {
        prev.reset();
        continue;
      }
      FramePyramid cur = build_frame_pyramid(read.frame.depth, &read.frame.color, source->camera());
      const SE3 T_w_cur = *read.frame.T_world_camera_gt;
      if (prev) {
        const SE3 T_true = T_w_prev.inverse() * T_w_cur;
        for (size_t k = 0; k < regs.size(); ++k) {
          const auto start = std::chrono::steady_clock::now();
          const RegistrationResult res = regs[k]->align(cur, *prev, SE3());
          rows[k].ms.push_back(elapsed_ms(start));
          const Errors e = error_of(res.T_ref_cur, T_true);
          rows[k].t_mm.push_back(e.t_mm);
          rows[k].r_deg.push_back(e.r_deg);
          rows[k].iterations.push_back(
              double(std::accumulate(res.iterations_per_level.begin(), res.iterations_per_level.end(), 0)));
          ++rows[k].statuses[to_string(res.status)];
          rows[k].eigen_ratio.push_back(res.eigenvalues(5) > 0.0 ? res.eigenvalues(0) / res.eigenvalues(5) : 0.0);
        }
        ++pairs;
      }
      prev = std::move(cur);
      T_w_prev = T_w_cur;
    }
    std::printf("\n### %s: %d pairs\n\n", name, pairs);
    std::printf("| lambda | backend | pairs | ms / registration | iterations | trans. error mean / median (mm) | "
                "rot. error mean / median (deg) | status |\n|---|---|---|---|---|---|---|---|\n");
    for (const Row& r : rows) print_row(r);
    std::printf("\nSmallest / largest balanced eigenvalue (the degeneracy test's ratio), min / 5th percentile / "
                "median over the pairs:\n\n");
    for (const Row& r : rows) {
      std::vector<double> v = r.eigen_ratio;
      std::sort(v.begin(), v.end());
      if (v.empty()) continue;
      std::printf("- lambda %s: %.2g / %.2g / %.2g\n", r.method.c_str(), v.front(), v[v.size() / 20], median(v));
    }
    std::fflush(stdout);
  }
  return 0;
}

// ---- Google Benchmark timings on one synthetic pair ------------------------------------------------------------

// The first pair of the room; first_level 1 builds its pyramids from 320x240 as the SLAM pipeline's default
// tracking_level does (slam/pipeline.h).
const Pair& bench_pair(int first_level = 0) {
  static const Pair pair0 = std::move(synthetic_pairs(1).pairs.front());
  if (first_level == 0) return pair0;
  static const Pair pair1 = std::move(synthetic_pairs(1, 1).pairs.front());
  return pair1;
}

void BM_BuildFramePyramid(benchmark::State& state) {
  datasets::SyntheticOptions options;
  options.frames = 1;
  datasets::SyntheticSequence seq(options);
  const datasets::SyntheticFrame f = seq.frame(0);
  for (auto _ : state) benchmark::DoNotOptimize(build_frame_pyramid(f.depth, &f.color, seq.camera()));
}
BENCHMARK(BM_BuildFramePyramid)->Unit(benchmark::kMillisecond)->UseRealTime();

void BM_Align(benchmark::State& state, const std::string& method, const std::string& backend, int first_level) {
  std::unique_ptr<Registration> reg;
  try {
    reg = make_registration(method, backend);
  } catch (const Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  const Pair& p = bench_pair(first_level);
  RegistrationResult res;
  for (auto _ : state) res = reg->align(p.cur, p.ref, SE3());
  const Errors e = error_of(res.T_ref_cur, p.T_ref_cur_true);
  state.counters["iterations"] =
      double(std::accumulate(res.iterations_per_level.begin(), res.iterations_per_level.end(), 0));
  state.counters["t_err_mm"] = e.t_mm;
  state.counters["r_err_deg"] = e.r_deg;
  for (size_t l = 0; l < res.iterations_per_level.size(); ++l) {
    state.counters["it_l" + std::to_string(l)] = double(res.iterations_per_level[l]);
  }
}

// The NDT methods' cell model of one frame alone (issue 17: Stoyanov found it costlier than the registration),
// to read against BM_Align of the same method, which includes it: the reference frame of the pair at the
// pipeline's 320x240 (first_level 1), sampled and built with the method's default resolutions and point stride.
// ndt-p2d builds it for the reference, ndt-d2d and mrsmap for both frames (twice this).
void BM_NdtCellModel(benchmark::State& state, const std::string& method) {
  const RegistrationOptions options = default_registration_options(method);
  const NdtOptions& o = options.method_as<NdtOptions>();
  const Pair& p = bench_pair(1);
  size_t cells = 0;
  for (auto _ : state) {
    const NdtSamples samples = sample_ndt(p.ref.levels[0], o.point_stride);
    const NdtModel model = build_ndt_model(samples.points, o.resolutions_m(), o.grid);
    cells = model.levels.back().size();
  }
  state.counters["finest_cells"] = double(cells);
}
BENCHMARK_CAPTURE(BM_NdtCellModel, ndt_p2d, std::string("ndt-p2d"))->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK_CAPTURE(BM_NdtCellModel, ndt_d2d, std::string("ndt-d2d"))->Unit(benchmark::kMillisecond)->UseRealTime();

// One reduction (one Gauss-Newton iteration's normal equations) at pyramid level `level` of the 640x480 pair for a
// registered per-pixel method, inputs already on the device. Its default options except: photometric rows on every
// finest-level pixel, no gradient threshold and Student-t weights on them (the problem this benchmark has always
// timed). `holder` keeps the method the problem points into.
ResidualProblem level_problem(const std::string& method, int level, std::unique_ptr<Registration>& holder) {
  const Pair& pair = bench_pair();
  RegistrationOptions options = default_registration_options(method);
  options.set("finest_level_photometric_step", 1);
  options.set("min_gradient", 0.0);
  options.for_each_option([](const char* key, auto& field) {
    if constexpr (std::is_same_v<std::remove_reference_t<decltype(field)>, RobustKernel>) {
      if (std::strcmp(key, "robust_rgb") == 0) field = RobustKernel::student_t;
    }
  });
  holder = make_registration(method, options, make_backend("cpu"));
  auto* gn = dynamic_cast<GaussNewtonRegistration*>(holder.get());
  if (gn == nullptr) throw Error(method + " is not a per-pixel method");
  ResidualProblem p = gn->level_problem(pair.cur, pair.ref, level, pair.T_ref_cur_true);
  p.inputs_version = 1;
  return p;
}

void run_reduce(benchmark::State& state, ReductionBackend& backend, const std::string& method, int level = 0) {
  std::unique_ptr<Registration> holder;
  const ResidualProblem p = level_problem(method, level, holder);
  NormalEquations ne = backend.reduce(p);  // uploads
  for (auto _ : state) ne = backend.reduce(p);
  state.counters["rows"] = double(ne.count);
}

void BM_Reduce_cpu(benchmark::State& state, const std::string& method) {
  CpuReductionBackend backend;
  run_reduce(state, backend, method, int(state.range(0)));
}

#ifdef HF_BENCH_HAVE_OPENCL
void BM_Reduce_opencl(benchmark::State& state, const std::string& method) {
  opencl::OpenClBackendOptions options;
  options.pixels_per_item = int(state.range(0));
  options.max_work_group_size = std::size_t(state.range(1));
  std::unique_ptr<opencl::OpenClReductionBackend> backend;
  try {
    backend = std::make_unique<opencl::OpenClReductionBackend>(opencl::Context::shared(), options);
  } catch (const Error& e) {
    state.SkipWithError(e.what());
    return;
  }
  state.counters["work_group"] = double(backend->work_group_size());
  run_reduce(state, *backend, method);
}
#endif

void register_benchmarks() {
  for (const std::string& name : registration_names()) {
    const std::string& id = name;
    // Argument: pyramid level (0 = 640x480).
    benchmark::RegisterBenchmark((std::string("BM_Reduce/") + name + "/cpu").c_str(), BM_Reduce_cpu, id)
        ->Arg(0)
        ->Arg(1)
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
#ifdef HF_BENCH_HAVE_OPENCL
    // Arguments: pixels per work-item, largest work-group size.
    benchmark::RegisterBenchmark((std::string("BM_Reduce/") + name + "/opencl").c_str(), BM_Reduce_opencl, id)
        ->Args({1, 256})
        ->Args({4, 256})
        ->Args({16, 256})
        ->Args({4, 64})
        ->Args({16, 64})
        ->Args({64, 16})
        ->Unit(benchmark::kMillisecond)
        ->UseRealTime();
#endif
  }
  for (const std::string& method : registration_names()) {
    for (const std::string& backend : backend_names()) {
      benchmark::RegisterBenchmark(("BM_Align/" + method + "/" + backend).c_str(), BM_Align, method, backend, 0)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(1.0);
      // The same 640x480 frames, registered from 320x240 (the pipeline's tracking_level 1).
      benchmark::RegisterBenchmark(("BM_AlignFromLevel1/" + method + "/" + backend).c_str(), BM_Align, method,
                                   backend, 1)
          ->Unit(benchmark::kMillisecond)
          ->UseRealTime()
          ->MinTime(1.0);
    }
  }
}

}  // namespace
}  // namespace hf

int main(int argc, char** argv) {
  bool accuracy = false, lambda_sweep = false;
  int max_pairs = 1000, pcl_pairs = 30, first_level = 0;
  std::vector<char*> rest;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--accuracy") == 0) {
      accuracy = true;
    } else if (std::strcmp(argv[i], "--lambda-sweep") == 0) {
      lambda_sweep = true;
    } else if (std::strcmp(argv[i], "--max-pairs") == 0 && i + 1 < argc) {
      max_pairs = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--pcl-pairs") == 0 && i + 1 < argc) {
      pcl_pairs = std::atoi(argv[++i]);
    } else if (std::strcmp(argv[i], "--first-level") == 0 && i + 1 < argc) {
      first_level = std::atoi(argv[++i]);
    } else {
      rest.push_back(argv[i]);
    }
  }
  try {
    if (accuracy) return hf::run_accuracy(max_pairs, pcl_pairs, first_level);
    if (lambda_sweep) return hf::run_lambda_sweep(max_pairs);
    int n = int(rest.size());
    hf::register_benchmarks();
    benchmark::Initialize(&n, rest.data());
    benchmark::RunSpecifiedBenchmarks();
    benchmark::Shutdown();
  } catch (const hf::Error& e) {
    std::fprintf(stderr, "bench_registration: %s\n", e.what());
    return 1;
  }
  return 0;
}
