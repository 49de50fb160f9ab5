// The OpenCL reduction backend against the C++ one and against exact sums (registration/opencl/).
// Every test skips with a message when no OpenCL platform is installed (e.g. no pocl-opencl-icd); the
// registration_opencl_no_platform CTest entry runs NoPlatform.* with the ICD loader pointed at an empty folder.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "core/error.h"
#include "datasets/synthetic_sequence.h"
#include "registration/cpu_backend.h"
#include "registration/frame_pyramid.h"
#include "registration/gauss_newton.h"
#include "registration/opencl/device_pyramid.h"
#include "registration/opencl/opencl_backend.h"
#include "reg_test_util.h"

namespace hf {
namespace {

bool have_opencl() { return !opencl::list_devices().empty(); }

#define HF_SKIP_WITHOUT_OPENCL()                                                                          \
  if (!have_opencl()) {                                                                                   \
    GTEST_SKIP() << "no OpenCL platform found (install pocl-opencl-icd): the OpenCL backend is not tested"; \
  }

// The exact double sums of rows, accumulated exactly as the C++ backend does (hf_reg_accumulate).
std::vector<double> double_sums(const std::vector<hf_reg_row>& rows) {
  std::vector<double> sums(HF_REG_SUMS, 0.0);
  for (const hf_reg_row& row : rows) hf_reg_accumulate(&row, sums.data());
  return sums;
}

std::vector<hf_reg_row> random_rows(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> J(-2.0f, 2.0f), r(-0.05f, 0.05f), w(0.0f, 1.0f);
  std::vector<hf_reg_row> rows(static_cast<size_t>(n));
  for (hf_reg_row& row : rows) {
    for (float& j : row.J) j = J(rng);
    row.r = r(rng);
    row.w = w(rng);
  }
  return rows;
}

double max_abs(const std::vector<double>& v) {
  double m = 0.0;
  for (double x : v) m = std::max(m, std::fabs(x));
  return m;
}

TEST(OpenClContext, ListsDevicesAndDescribesTheChosenOne) {
  HF_SKIP_WITHOUT_OPENCL();
  auto ctx = opencl::Context::shared();
  EXPECT_FALSE(ctx->info().device_name.empty());
  EXPECT_GE(ctx->info().max_work_group_size, 1u);
  EXPECT_NE(ctx->info().describe().find(ctx->info().device_name), std::string::npos);
  // Shared while held: a second request gets the same context (programs are built once).
  EXPECT_EQ(opencl::Context::shared().get(), ctx.get());
}

TEST(OpenClContext, UnknownDeviceSpecIsAnErrorListingTheDevices) {
  HF_SKIP_WITHOUT_OPENCL();
  try {
    opencl::Context ctx("no-such-device-zz9");
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("no-such-device-zz9"), std::string::npos) << what;
    EXPECT_NE(what.find(opencl::list_devices().front().device_name), std::string::npos) << what;
  }
  EXPECT_THROW(opencl::Context("7:7"), Error);
  // Index and type specs pick the listed device.
  const opencl::DeviceInfo first = opencl::list_devices().front();
  opencl::Context by_index(std::to_string(first.platform_index) + ":" + std::to_string(first.device_index));
  EXPECT_EQ(by_index.info().device_name, first.device_name);
}

TEST(OpenClContext, CompileErrorSurfacesWithTheBuildLog) {
  HF_SKIP_WITHOUT_OPENCL();
  auto ctx = opencl::Context::shared();
  const std::string broken = "__kernel void broken(__global float* x) { x[0] = hf_no_such_identifier_42; }\n";
  try {
    ctx->program("test-broken", broken);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("failed to build"), std::string::npos) << what;
    EXPECT_NE(what.find("test-broken"), std::string::npos) << what;
    // The build log names the offending identifier.
    EXPECT_NE(what.find("hf_no_such_identifier_42"), std::string::npos) << what;
  }
}

TEST(OpenClContext, ProgramsAreBuiltOncePerKey) {
  HF_SKIP_WITHOUT_OPENCL();
  auto ctx = opencl::Context::shared();
  const std::string src = "__kernel void twice(__global float* x) { x[get_global_id(0)] *= 2.0f; }\n";
  cl::Program a = ctx->program("test-twice", src);
  cl::Program b = ctx->program("test-twice", src);
  EXPECT_EQ(a(), b());
  EXPECT_THROW(ctx->program("test-twice", src, "-DX=1"), Error);
}

TEST(OpenClContext, EmbeddedSourceInlinesTheSharedHeaders) {
  const std::string_view src = opencl::registration_program_source();
  // Every registered per-pixel method's kernel is in the program.
  for (const std::string& name : registration_names()) {
    const test::MethodUnderTest m = test::method_under_test(name);
    if (m.dense == nullptr) continue;
    EXPECT_NE(src.find("HF_REG_OPENCL_KERNEL(" + name + ","), std::string_view::npos) << name;
  }
  EXPECT_NE(src.find("#line 1 \"registration/kernels/reg_common.h\""), std::string_view::npos);
  EXPECT_NE(src.find("#line 1 \"core/kernels/cl_compat.h\""), std::string_view::npos);
  EXPECT_EQ(src.find("\n#include \"registration/"), std::string_view::npos);  // all inlined
}

class OpenClRows : public ::testing::TestWithParam<int> {};

TEST_P(OpenClRows, ReductionOfKnownRowsEqualsTheDoubleSum) {
  HF_SKIP_WITHOUT_OPENCL();
  opencl::OpenClBackendOptions options;
  options.pixels_per_item = GetParam();
  opencl::OpenClReductionBackend backend(opencl::Context::shared(), options);
  // Not a multiple of any work-group size, so partial groups and idle items are exercised.
  for (int n : {0, 1, 7, 1000, 100003}) {
    const std::vector<hf_reg_row> rows = random_rows(n, 17u + unsigned(n));
    const std::vector<double> expected = double_sums(rows);
    const std::vector<double> got = backend.reduce_rows(rows);
    ASSERT_EQ(got.size(), size_t(HF_REG_SUMS));
    // Double accumulation reorders additions of ~1e5 terms: a few ulps of the largest sum. Float accumulation
    // (devices without fp64) is a pairwise tree: ~log2(n) float roundings.
    const double tol = (backend.accumulates_in_double() ? 1e-12 : 1e-5) * std::max(1.0, max_abs(expected));
    for (int k = 0; k < HF_REG_SUMS; ++k) EXPECT_NEAR(got[size_t(k)], expected[size_t(k)], tol) << "n=" << n << " k=" << k;
    EXPECT_EQ(got[HF_REG_SUM_COUNT], double(n));
  }
}

INSTANTIATE_TEST_SUITE_P(PixelsPerItem, OpenClRows, ::testing::Values(1, 4, 33));

// Two-level pyramids of two frames of the synthetic room with sensor noise, at 160x120 so that each test process
// (CTest runs every case on its own, also under ASan) renders them in well under a second.
struct FramePair {
  FramePyramid cur, ref;
  SE3 T_ref_cur_true;
};

const FramePair& opencl_room_pair() {
  static const FramePair pair = [] {
    datasets::SyntheticOptions options;
    options.preset = "room";
    options.frames = 10;
    options.camera = PinholeCamera::preset("ros").scaled(2);
    datasets::SyntheticSequence seq(options);
    const datasets::SyntheticFrame a = seq.frame(0), b = seq.frame(3);
    FramePyramidOptions po;
    po.levels = 2;
    FramePair p;
    p.ref = build_frame_pyramid(a.depth, &a.color, seq.camera(), po);
    p.cur = build_frame_pyramid(b.depth, &b.color, seq.camera(), po);
    p.T_ref_cur_true = a.T_world_camera.inverse() * b.T_world_camera;
    return p;
  }();
  return pair;
}

// A registered method's level problem on the room pair at T, with every robust kernel set to `robust`. The
// problem points into `method`, which the caller keeps.
ResidualProblem make_problem(const FramePair& pair, int level, const std::string& name, RobustKernel robust,
                             const SE3& T, test::MethodUnderTest& method, double depth_noise_ref_m = 0.0) {
  RegistrationOptions options = default_registration_options(name);
  test::set_robust_kernels(options, robust);
  options.set("depth_noise_ref_m", depth_noise_ref_m);
  options.set("finest_level_photometric_step", 1);
  options.set("min_gradient", 0.0);
  method = test::method_under_test(name, options, make_backend("cpu"));
  if (method.dense == nullptr) return ResidualProblem{};
  ResidualProblem p = method.dense->level_problem(pair.cur, pair.ref, level, T);
  p.inputs_version = 1;
  return p;
}

double max_abs_diff(const Matrix6d& a, const Matrix6d& b) { return (a - b).cwiseAbs().maxCoeff(); }

using MethodCase = std::tuple<std::string, RobustKernel>;
class BackendsAgree : public ::testing::TestWithParam<MethodCase> {};

TEST_P(BackendsAgree, OnTheNormalEquationsAndTheSolvedStep) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  const auto& [name, robust] = GetParam();
  const std::string label = name + "/" + test::robust_name(robust);
  CpuReductionBackend cpu;
  opencl::OpenClReductionBackend cl_backend;
  // Start 1 cm / ~0.6 degrees off the true motion so the step is a real correction, at both levels.
  Vector6d delta;
  delta << 0.004, -0.006, 0.008, 0.01, -0.004, 0.006;
  const SE3 T0 = SE3::exp(delta) * pair.T_ref_cur_true;
  for (int level = 0; level < 2; ++level) {
    test::MethodUnderTest method;
    ResidualProblem p = make_problem(pair, level, name, robust, T0, method);
    if (method.dense == nullptr) GTEST_SKIP() << name << " is not a per-pixel method";
    p.inputs_version = std::uint64_t(level + 1);
    const NormalEquations a = cpu.reduce(p);
    const NormalEquations b = cl_backend.reduce(p);
    ASSERT_GT(a.count, 500) << label << " level " << level;
    EXPECT_EQ(a.count, b.count) << label << " level " << level;
    // 1e-6 relative (to the largest entry) on H, g and the cost.
    EXPECT_LE(max_abs_diff(a.JtJ, b.JtJ), 1e-6 * a.JtJ.cwiseAbs().maxCoeff()) << label << " level " << level;
    EXPECT_LE((a.Jtr - b.Jtr).cwiseAbs().maxCoeff(), 1e-6 * a.Jtr.cwiseAbs().maxCoeff()) << label;
    EXPECT_NEAR(a.cost, b.cost, 1e-6 * a.cost) << label;
    // The step the driver would take, from the driver's own solver: 1e-9 (radians, metres).
    const GaussNewtonStep sa = solve_gauss_newton_step(a.JtJ, a.Jtr, 1e-6);
    const GaussNewtonStep sb = solve_gauss_newton_step(b.JtJ, b.Jtr, 1e-6);
    ASSERT_TRUE(sa.finite && sb.finite);
    EXPECT_GT(sa.xi.norm(), 1e-4) << label << ": the step should be a real correction";
    EXPECT_LE((sa.xi - sb.xi).cwiseAbs().maxCoeff(), 1e-9)
        << label << " level " << level << "\ncpu    " << sa.xi.transpose() << "\nopencl " << sb.xi.transpose();
  }
}

INSTANTIATE_TEST_SUITE_P(Registry, BackendsAgree,
                         ::testing::Combine(::testing::ValuesIn(registration_names()),
                                            ::testing::Values(RobustKernel::none, RobustKernel::huber,
                                                              RobustKernel::student_t)),
                         [](const auto& info) {
                           std::string name = std::get<0>(info.param);  // registry keys may hold '-' (ndt-p2d)
                           for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
                           return name + "_" + test::robust_name(std::get<1>(info.param));
                         });

// icp's depth-noise weighting (IcpOptions::depth_noise_ref_m; the room's depths straddle 1.5 m) in icp and in
// combined's icp term: the same 1e-6 relative agreement.
TEST(OpenClBackend, IcpDepthNoiseWeightingAgrees) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  CpuReductionBackend cpu;
  opencl::OpenClReductionBackend cl_backend;
  for (const char* name : {"icp", "combined"}) {
    for (int level = 0; level < 2; ++level) {
      test::MethodUnderTest method, plain;
      ResidualProblem p = make_problem(pair, level, name, RobustKernel::huber, pair.T_ref_cur_true, method, 1.5);
      p.inputs_version = std::uint64_t(level + 1);
      const NormalEquations a = cpu.reduce(p), b = cl_backend.reduce(p);
      const NormalEquations unweighted =
          cpu.reduce(make_problem(pair, level, name, RobustKernel::huber, pair.T_ref_cur_true, plain));
      ASSERT_GT(a.count, 500) << name << " level " << level;
      EXPECT_EQ(a.count, b.count) << name << " level " << level;
      EXPECT_EQ(a.count, unweighted.count) << name << ": the weighting rejects no row";
      EXPECT_LT(a.JtJ.trace(), unweighted.JtJ.trace()) << name << ": rows beyond 1.5 m count less";
      EXPECT_LE(max_abs_diff(a.JtJ, b.JtJ), 1e-6 * a.JtJ.cwiseAbs().maxCoeff()) << name << " level " << level;
      EXPECT_LE((a.Jtr - b.Jtr).cwiseAbs().maxCoeff(), 1e-6 * a.Jtr.cwiseAbs().maxCoeff()) << name;
      EXPECT_NEAR(a.cost, b.cost, 1e-6 * a.cost) << name;
    }
  }
}

TEST(OpenClBackend, ReusesUploadedMapsWhileTheInputsVersionHolds) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  opencl::OpenClReductionBackend backend;
  test::MethodUnderTest method;
  ResidualProblem p = make_problem(pair, 1, "combined", RobustKernel::huber, pair.T_ref_cur_true, method);
  p.inputs_version = 42;
  const NormalEquations first = backend.reduce(p);
  EXPECT_EQ(backend.uploads(), 1u);
  // A new pose only (the next iteration): no upload, different equations.
  Vector6d delta;
  delta << 0.0, 0.0, 0.01, 0.0, 0.0, 0.0;
  p.T_ref_cur = to_transform12(SE3::exp(delta) * pair.T_ref_cur_true);
  const NormalEquations moved = backend.reduce(p);
  EXPECT_EQ(backend.uploads(), 1u);
  EXPECT_GT((moved.JtJ - first.JtJ).cwiseAbs().maxCoeff(), 0.0);
  // Same inputs again: bit-identical (deterministic group order and host sum).
  p.T_ref_cur = to_transform12(pair.T_ref_cur_true);
  const NormalEquations again = backend.reduce(p);
  EXPECT_EQ(again.to_sums(), first.to_sums());
  // A new version (the next level or frame) uploads again, and so does a different map pointer.
  p.inputs_version = 43;
  backend.reduce(p);
  EXPECT_EQ(backend.uploads(), 2u);
  p = make_problem(pair, 0, "combined", RobustKernel::huber, pair.T_ref_cur_true, method);
  p.inputs_version = 43;
  const NormalEquations level0 = backend.reduce(p);
  EXPECT_EQ(backend.uploads(), 3u);
  CpuReductionBackend cpu;
  EXPECT_EQ(level0.count, cpu.reduce(p).count);
}

// A method's KernelBuffer (sdf: the map's flat hash and pool) is uploaded once per buffer version, not per inputs
// version: the next iteration or a re-bound level with the same map reads the device copy it has.
TEST(OpenClBackend, UploadsAKernelBufferOncePerVersion) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  test::MethodUnderTest method;
  ResidualProblem p = make_problem(pair, 1, "sdf", RobustKernel::huber, pair.T_ref_cur_true, method);
  ASSERT_NE(p.maps[HF_REG_IN_METHOD0].buffer, nullptr);
  opencl::OpenClReductionBackend backend;
  CpuReductionBackend cpu;
  const NormalEquations first = backend.reduce(p);
  EXPECT_EQ(backend.buffer_uploads(), 2u);  // the table and the pool
  p.inputs_version += 1;                    // the per-pixel maps again, the map's copy kept
  const NormalEquations again = backend.reduce(p);
  EXPECT_EQ(backend.uploads(), 2u);
  EXPECT_EQ(backend.buffer_uploads(), 2u);
  EXPECT_EQ(again.to_sums(), first.to_sums());
  EXPECT_EQ(first.count, cpu.reduce(p).count);
  // The method fuses its own map again for the next level problem: a new version, uploaded again.
  p = make_problem(pair, 1, "sdf", RobustKernel::huber, pair.T_ref_cur_true, method);
  backend.reduce(p);
  EXPECT_EQ(backend.buffer_uploads(), 4u);
}

// The largest difference between two maps of one level (float4 maps: x, y, z; w, the validity, must agree), and
// how many validity flags differ.
struct MapGap {
  double max_abs = 0.0;
  long flags = 0;
};
MapGap gap(const Image<hf_float4>& a, const Image<hf_float4>& b) {
  MapGap g;
  for (size_t i = 0; i < a.size(); ++i) {
    const hf_float4 p = a.data()[i], q = b.data()[i];
    if (p.w != q.w) {
      ++g.flags;
      continue;
    }
    g.max_abs = std::max({g.max_abs, double(std::fabs(p.x - q.x)), double(std::fabs(p.y - q.y)),
                          double(std::fabs(p.z - q.z))});
  }
  return g;
}
double gap(const Image<float>& a, const Image<float>& b) {
  double m = 0.0;
  for (size_t i = 0; i < a.size(); ++i) m = std::max(m, double(std::fabs(a.data()[i] - b.data()[i])));
  return m;
}

// The frame pyramid on the device (registration/opencl/device_pyramid.h) against build_frame_pyramid: without
// the bilateral filter every step is the same float operations (the shared per-pixel functions, no contraction,
// correctly rounded division and square root), so the maps are equal; with it, the device's exp differs from the
// C++ one by ulps, so the filtered depth moves by float rounding (~1e-7 relative) and normals by as little.
TEST(DeviceFramePyramid, MatchesTheCpuPyramid) {
  HF_SKIP_WITHOUT_OPENCL();
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = 2;
  options.camera = PinholeCamera::preset("ros").scaled(1);  // 320x240
  const datasets::SyntheticSequence seq(options);
  const datasets::SyntheticFrame f = seq.frame(1);
  opencl::DeviceFramePyramid device;
  for (const bool bilateral : {false, true}) {
    for (const int first_level : {0, 1}) {
      FramePyramidOptions po;
      po.levels = 3;
      po.bilateral_filter = bilateral;
      po.first_level = first_level;
      po.max_depth_m = 4.0f;
      const FramePyramid a = build_frame_pyramid(f.depth, &f.color, seq.camera(), po);
      const FramePyramid b = device.build(f.depth, &f.color, seq.camera(), po);
      ASSERT_EQ(b.num_levels(), a.num_levels());
      for (int l = 0; l < a.num_levels(); ++l) {
        const FramePyramidLevel &x = a.levels[size_t(l)], &y = b.levels[size_t(l)];
        const std::string label = "bilateral " + std::to_string(bilateral) + " first_level " +
                                  std::to_string(first_level) + " level " + std::to_string(l);
        ASSERT_EQ(y.vertices.width(), x.vertices.width()) << label;
        ASSERT_EQ(y.camera.width, x.camera.width) << label;
        const MapGap v = gap(x.vertices, y.vertices), n = gap(x.normals, y.normals);
        std::printf("%s: vertices %.2e m (%ld flags), normals %.2e (%ld), intensity %.2e, gradients %.2e\n",
                    label.c_str(), v.max_abs, v.flags, n.max_abs, n.flags, gap(x.intensity, y.intensity),
                    std::max(gap(x.grad_x, y.grad_x), gap(x.grad_y, y.grad_y)));
        EXPECT_EQ(v.flags, 0) << label;
        EXPECT_EQ(n.flags, 0) << label;
        EXPECT_LE(v.max_abs, bilateral ? 1e-5 : 0.0) << label;
        EXPECT_LE(n.max_abs, bilateral ? 1e-3 : 0.0) << label;
        EXPECT_EQ(gap(x.intensity, y.intensity), 0.0) << label;
        EXPECT_EQ(gap(x.grad_x, y.grad_x), 0.0) << label;
        EXPECT_EQ(gap(x.grad_y, y.grad_y), 0.0) << label;
      }
    }
  }
  // No valid depth and no colour: empty maps, as on the CPU.
  const DepthImage nan_depth(f.depth.width(), f.depth.height(), std::numeric_limits<float>::quiet_NaN());
  const FramePyramid none = device.build(nan_depth, nullptr, seq.camera());
  for (const FramePyramidLevel& level : none.levels) {
    EXPECT_EQ(count_valid_pixels(level.vertices), 0);
    EXPECT_FALSE(level.has_intensity());
  }
  FramePyramidOptions holes;
  holes.fill_holes_levels = 2;
  EXPECT_THROW(device.build(f.depth, &f.color, seq.camera(), holes), Error);
  EXPECT_THROW(device.build(f.depth, &f.color, seq.camera().scaled(1)), Error);
}

// Residency (core/device_copy.h): the device pyramid's levels stay on the device as their host images' copies, so
// the reduction binds them and uploads no map; the poses are those of the same registration over host copies of the
// same images (uploaded: same bytes, same kernels, so bit for bit). Dropping the copies makes the backend upload.
TEST(OpenClBackend, BindsTheDevicePyramidsMapsInsteadOfUploadingThem) {
  HF_SKIP_WITHOUT_OPENCL();
  datasets::SyntheticOptions options;
  options.preset = "room";
  options.frames = 4;
  options.camera = PinholeCamera::preset("ros").scaled(2);  // 160x120
  const datasets::SyntheticSequence seq(options);
  const datasets::SyntheticFrame a = seq.frame(0), b = seq.frame(3);
  opencl::DeviceFramePyramid device;
  FramePyramid reference = device.build(a.depth, &a.color, seq.camera());
  FramePyramid current = device.build(b.depth, &b.color, seq.camera());
  // Every map of every level has its copy.
  for (const FramePyramid* p : {&reference, &current})
    for (const FramePyramidLevel& level : p->levels) EXPECT_EQ(level.device_copies.size(), 5u);
  // Host copies of the same images (a copied level's images live elsewhere: no copy matches them).
  FramePyramid host_reference = reference, host_current = current;
  for (const std::string name : {"icp", "combined"}) {
    auto backend = std::make_unique<opencl::OpenClReductionBackend>();
    const opencl::OpenClReductionBackend* counters = backend.get();
    const auto reg = make_registration(name, default_registration_options(name), std::move(backend));
    const RegistrationResult on_device = reg->align(current, reference, SE3());
    EXPECT_EQ(counters->map_uploads(), 0u) << name;
    EXPECT_GT(counters->resident_binds(), 0u) << name;
    const RegistrationResult uploaded = reg->align(host_current, host_reference, SE3());
    EXPECT_GT(counters->map_uploads(), 0u) << name;
    EXPECT_EQ(on_device.status, uploaded.status) << name;
    EXPECT_EQ((on_device.T_ref_cur.matrix() - uploaded.T_ref_cur.matrix()).cwiseAbs().maxCoeff(), 0.0) << name;
    EXPECT_LT(test::translation_error_m(on_device.T_ref_cur, a.T_world_camera.inverse() * b.T_world_camera), 0.01)
        << name;
  }
  // Without the tokens the entries are gone: the same images are uploaded.
  auto backend = std::make_unique<opencl::OpenClReductionBackend>();
  const opencl::OpenClReductionBackend* counters = backend.get();
  const auto reg = make_registration("icp", default_registration_options("icp"), std::move(backend));
  for (FramePyramid* p : {&reference, &current})
    for (FramePyramidLevel& level : p->levels) level.device_copies.clear();
  reg->align(current, reference, SE3());
  EXPECT_GT(counters->map_uploads(), 0u);
  EXPECT_EQ(counters->resident_binds(), 0u);
  // Residency off (for measurements): nothing is published.
  const auto ctx = opencl::Context::shared();
  ctx->set_residency_enabled(false);
  const FramePyramid unpublished = device.build(a.depth, &a.color, seq.camera());
  ctx->set_residency_enabled(true);
  for (const FramePyramidLevel& level : unpublished.levels) EXPECT_TRUE(level.device_copies.empty());
}

// build_model on the device against build_model_pyramid: the same float operations (z of the vertices, the
// depth-aware halving, back-projection, normals), so equal maps; level 0's copies are published for its images.
TEST(DeviceFramePyramid, ModelPyramidMatchesTheCpus) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  const FramePyramidLevel& model = pair.ref.levels[0];
  opencl::DeviceFramePyramid device;
  const FramePyramid a = build_model_pyramid(model.vertices, model.normals, nullptr, model.camera, 3);
  const FramePyramid b = device.build_model(model.vertices, model.normals, model.camera, 3);
  ASSERT_EQ(b.num_levels(), 3);
  for (int l = 0; l < 3; ++l) {
    const FramePyramidLevel &x = a.levels[size_t(l)], &y = b.levels[size_t(l)];
    EXPECT_EQ(y.camera.width, x.camera.width);
    const MapGap v = gap(x.vertices, y.vertices), n = gap(x.normals, y.normals);
    EXPECT_EQ(v.flags + n.flags, 0) << "level " << l;
    EXPECT_EQ(v.max_abs, 0.0) << "level " << l;
    EXPECT_EQ(n.max_abs, 0.0) << "level " << l;
    EXPECT_FALSE(y.has_intensity());
    EXPECT_EQ(y.device_copies.size(), 2u);
  }
  EXPECT_THROW(device.build_model(model.vertices, model.normals, model.camera.scaled(1), 3), Error);
  EXPECT_THROW(device.build_model(model.vertices, model.normals, model.camera, 0), Error);
}

// sdf on the device meets the inputs that leave its map or its frame empty (no valid depth, one valid pixel, as
// either frame) with the cpu backend's status and pose: an empty map is a flat table of empty entries, not a
// zero-sized buffer, and a frame without rows reduces to nothing on both.
TEST(OpenClBackend, SdfOnEmptyInputGivesTheCpuOutcome) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  const PinholeCamera cam = pair.cur.levels[0].camera;
  const SE3 guess = SE3::exp((Vector6d() << 0.01, 0.0, 0.0, 0.02, 0.0, 0.0).finished());
  FramePyramidOptions po;
  po.levels = 2;
  for (const int valid : {0, 1}) {
    DepthImage depth(cam.width, cam.height, std::numeric_limits<float>::quiet_NaN());
    for (int i = 0; i < valid; ++i) depth(cam.width / 2, cam.height / 2) = 1.5f;
    const FramePyramid empty = build_frame_pyramid(depth, nullptr, cam, po);
    for (const bool empty_is_current : {true, false}) {
      RegistrationResult r[2];
      for (int b = 0; b < 2; ++b) {
        auto reg =
            make_registration("sdf", default_registration_options("sdf"), make_backend(b == 0 ? "cpu" : "opencl"));
        r[b] = empty_is_current ? reg->align(empty, pair.ref, guess) : reg->align(pair.cur, empty, guess);
        test::expect_finite(r[b]);
      }
      const std::string label = "valid " + std::to_string(valid) + (empty_is_current ? " current" : " reference");
      EXPECT_EQ(r[1].status, r[0].status) << label << ": " << r[1].message;
      EXPECT_NE(r[1].status, RegistrationStatus::good) << label;
      EXPECT_LT(test::translation_error_m(r[1].T_ref_cur, r[0].T_ref_cur), 1e-9) << label;
    }
  }
}

TEST(OpenClBackend, MapsAMethodDoesNotReadMayBeNull) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  test::MethodUnderTest method;
  ResidualProblem p = make_problem(pair, 1, "icp", RobustKernel::none, pair.T_ref_cur_true, method);
  for (int slot : {HF_REG_IN_CUR_INTENSITY, HF_REG_IN_REF_INTENSITY, HF_REG_IN_REF_GRAD_X, HF_REG_IN_REF_GRAD_Y}) {
    EXPECT_EQ(p.maps[slot].data, nullptr);  // the driver binds only what icp reads
  }
  opencl::OpenClReductionBackend backend;
  CpuReductionBackend cpu;
  EXPECT_EQ(backend.reduce(p).count, cpu.reduce(p).count);
}

TEST(OpenClBackend, MalformedProblemIsAnError) {
  HF_SKIP_WITHOUT_OPENCL();
  const FramePair& pair = opencl_room_pair();
  test::MethodUnderTest method;
  ResidualProblem p = make_problem(pair, 1, "photometric", RobustKernel::none, pair.T_ref_cur_true, method);
  p.maps[HF_REG_IN_REF_GRAD_X] = {};
  opencl::OpenClReductionBackend backend;
  EXPECT_THROW(backend.reduce(p), Error);
  p = make_problem(pair, 1, "icp", RobustKernel::none, pair.T_ref_cur_true, method);
  p.camera.width = 0;
  EXPECT_THROW(backend.reduce(p), Error);
}

TEST(OpenClBackend, IsTheOpenclEntryOfTheBackendRegistry) {
  HF_SKIP_WITHOUT_OPENCL();
  std::unique_ptr<ReductionBackend> backend = make_backend("opencl");
  EXPECT_EQ(backend->name(), "opencl");
}

// Run by CTest with OCL_ICD_VENDORS pointing at an empty folder (registration_opencl_no_platform); in the normal
// run it only checks the message when the machine really has no platform.
TEST(NoPlatform, OpenclBackendFailsWithAClearMessage) {
  if (have_opencl()) GTEST_SKIP() << "an OpenCL platform is present; this case runs under registration_opencl_no_platform";
  try {
    make_opencl_backend();
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no OpenCL platform found: install pocl-opencl-icd or use --backend cpu"),
              std::string::npos)
        << e.what();
  }
  EXPECT_THROW(make_backend("opencl"), Error);
  EXPECT_NO_THROW(make_backend("cpu"));
}

}  // namespace
}  // namespace hf
