// The reduction contract: the 29 sums, the cpu backend against a naive double sum of the same rows, the
// degeneracy-aware solve, and the registries.
#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <optional>
#include <random>

#include "core/error.h"
#include "reg_test_util.h"
#include "registration/combined.h"
#include "registration/cpu_backend.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/icp_kernel.h"
#include "registration/reduction.h"
#include "registration/registration.h"

namespace hf {
namespace {

// Random but plausible maps: a bumpy surface at 1..3 m with random normals facing the camera and a textured
// intensity, so every method finds many correspondences at a small offset pose.
struct RandomMaps {
  hf_intrinsics K{100.0f, 100.0f, 31.5f, 23.5f, 64, 48};
  std::vector<hf_float4> cv, cn, rv, rn;
  std::vector<float> ci, ri, gx, gy;

  explicit RandomMaps(unsigned seed, int width = 64, int height = 48) {
    K.width = width;
    K.height = height;
    K.cx = 0.5f * float(width - 1);
    K.cy = 0.5f * float(height - 1);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f);
    const size_t n = size_t(K.width) * K.height;
    for (auto* v : {&cv, &cn, &rv, &rn}) v->resize(n);
    for (auto* v : {&ci, &ri, &gx, &gy}) v->resize(n);
    for (int y = 0; y < K.height; ++y) {
      for (int x = 0; x < K.width; ++x) {
        const size_t i = size_t(y) * K.width + x;
        const float z = 2.0f + 0.3f * std::sin(0.2f * x) + 0.2f * std::cos(0.3f * y);
        const bool hole = (x * 7 + y * 13) % 17 == 0;
        cv[i] = hole ? hf_invalid4() : hf_backproject(K, float(x), float(y), z + 0.001f * u(rng));
        rv[i] = hf_backproject(K, float(x), float(y), z);
        float nx = 0.3f * u(rng), ny = 0.3f * u(rng);
        const float len = std::sqrt(nx * nx + ny * ny + 1.0f);
        cn[i] = hole ? hf_invalid4() : hf_make_float4(nx / len, ny / len, -1.0f / len, 1.0f);
        rn[i] = hf_make_float4(nx / len, ny / len, -1.0f / len, 1.0f);
        ci[i] = 0.5f + 0.4f * std::sin(0.5f * x + 0.2f * y) + 0.01f * u(rng);
        ri[i] = 0.5f + 0.4f * std::sin(0.5f * x + 0.2f * y);
        gx[i] = 0.2f * std::cos(0.5f * x + 0.2f * y);
        gy[i] = 0.08f * std::cos(0.5f * x + 0.2f * y);
      }
    }
  }

  // The maps as one-level pyramids (current, reference).
  FramePyramid pyramid(bool current) const {
    FramePyramidLevel level;
    level.camera.fx = K.fx;
    level.camera.fy = K.fy;
    level.camera.cx = K.cx;
    level.camera.cy = K.cy;
    level.camera.width = K.width;
    level.camera.height = K.height;
    auto fill = [&](auto& image, const auto& values) {
      image = std::remove_reference_t<decltype(image)>(K.width, K.height);
      std::copy(values.begin(), values.end(), image.data());
    };
    fill(level.vertices, current ? cv : rv);
    fill(level.normals, current ? cn : rn);
    fill(level.intensity, current ? ci : ri);
    fill(level.grad_x, gx);  // the current frame's gradients are never read
    fill(level.grad_y, gy);
    FramePyramid p;
    p.levels.push_back(std::move(level));
    return p;
  }
};

const SE3 kOffset = SE3::exp((Vector6d() << 0.01, -0.02, 0.005, 0.01, 0.02, -0.01).finished());

// One registered method's level-0 problem on the random maps, with its options (default: the method's defaults,
// occlusion check on and a 0.3 photometric weight where the method has them).
struct MethodProblem {
  FramePyramid cur, ref;
  test::MethodUnderTest method;
  ResidualProblem problem;

  MethodProblem(const RandomMaps& maps, const std::string& name, RegistrationOptions options)
      : cur(maps.pyramid(true)), ref(maps.pyramid(false)) {
    options.set("rgb_weight", 0.3);
    method = test::method_under_test(name, options, make_backend("cpu"));
    if (method.dense != nullptr) problem = method.dense->level_problem(cur, ref, 0, kOffset);
  }
  // Rows on every pixel (photometric's and sdf's finest-level grids at 1).
  MethodProblem(const RandomMaps& maps, const std::string& name) : MethodProblem(maps, name, every_pixel(name)) {}

  static RegistrationOptions every_pixel(const std::string& name) {
    RegistrationOptions o = default_registration_options(name);
    o.set("finest_level_photometric_step", 1);
    o.set("finest_level_step", 1);
    return o;
  }
};

// The naive reference: every row of every pixel, in pixel order, in one double sum written out longhand.
NormalEquations naive_sum(const ResidualProblem& p) {
  NormalEquations ne;
  for (int y = 0; y < p.height(); ++y) {
    for (int x = 0; x < p.width(); ++x) {
      hf_reg_row rows[HF_REG_MAX_ROWS];
      const hf_reg_maps maps = p.kernel_maps();
      const int n = p.kernel->pixel(x, y, &maps, p.camera, p.T_ref_cur, p.params, rows);
      for (int k = 0; k < n; ++k) {
        Vector6d J;
        for (int i = 0; i < 6; ++i) J(i) = rows[k].J[i];
        ne.JtJ += double(rows[k].w) * J * J.transpose();
        ne.Jtr += double(rows[k].w) * J * double(rows[k].r);
        ne.cost += double(rows[k].w) * double(rows[k].r) * double(rows[k].r);
        ++ne.count;
      }
    }
  }
  return ne;
}

class CpuBackend : public ::testing::TestWithParam<std::string> {};

TEST_P(CpuBackend, EqualsNaiveDoubleSum) {
  const RandomMaps maps(7);
  const MethodProblem mp(maps, GetParam());
  if (mp.method.dense == nullptr) GTEST_SKIP() << GetParam() << " is not a per-pixel method";
  const ResidualProblem& p = mp.problem;
  CpuReductionBackend backend(5);  // chunks that do not divide the height
  const NormalEquations got = backend.reduce(p);
  const NormalEquations want = naive_sum(p);
  ASSERT_GT(want.count, 1000);
  EXPECT_EQ(got.count, want.count);
  const double scale = want.JtJ.cwiseAbs().maxCoeff();
  EXPECT_LE((got.JtJ - want.JtJ).cwiseAbs().maxCoeff(), 1e-12 * scale);
  EXPECT_LE((got.Jtr - want.Jtr).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, want.Jtr.cwiseAbs().maxCoeff()));
  EXPECT_NEAR(got.cost, want.cost, 1e-12 * std::max(1.0, want.cost));
  EXPECT_TRUE(got.JtJ.isApprox(got.JtJ.transpose()));
}

TEST_P(CpuBackend, DeterministicAcrossChunkings) {
  const RandomMaps maps(11);
  const MethodProblem mp(maps, GetParam());
  if (mp.method.dense == nullptr) GTEST_SKIP() << GetParam() << " is not a per-pixel method";
  const ResidualProblem& p = mp.problem;
  CpuReductionBackend a(8);
  const NormalEquations x = a.reduce(p), y = a.reduce(p);
  // Same chunking: bit-identical whatever the thread scheduling.
  EXPECT_EQ(x.to_sums(), y.to_sums());
}

INSTANTIATE_TEST_SUITE_P(Registry, CpuBackend, ::testing::ValuesIn(registration_names()), [](const auto& info) {
  std::string name = info.param;  // registry keys may hold '-' (ndt-p2d): not a test name character
  for (char& c : name) c = std::isalnum(static_cast<unsigned char>(c)) ? c : '_';
  return name;
});

// A method's AVX2 path (DenseKernel::rows_avx2, registration/cpu_backend_avx2.h) evaluates its scalar kernel's
// rows bit for bit, so against the pixel-by-pixel loop only the order of the double sums differs: agreement to
// 1e-12 relative; a method without one runs its pixel loop on the vectorised backend too (the same rows, never
// none). Covered for every registered method: widths that are and are not multiples of the eight lanes,
// photometric grids 1-3, every robust kernel, icp's depth-noise weighting off and on, and invalid pixels whose other
// fields are NaN (the lanes' masks must keep them out, as the scalar kernel's early returns do).
TEST_P(CpuBackend, VectorisedPathGivesThePixelLoopsRows) {
  CpuReductionBackend simd(5, true), scalar(5, false);
  if (!simd.vectorised()) GTEST_SKIP() << "this processor has no AVX2: only the pixel loop runs here";
  EXPECT_FALSE(scalar.vectorised());
  const std::string name = GetParam();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const auto& [width, height] : {std::pair{64, 48}, std::pair{61, 47}, std::pair{13, 9}}) {
    RandomMaps maps(21, width, height);
    for (size_t i = 0; i < maps.cv.size(); i += 5) maps.cv[i] = hf_make_float4(nan, nan, nan, 0.0f);
    for (size_t i = 2; i < maps.rv.size(); i += 7) maps.rv[i] = hf_make_float4(nan, nan, nan, 0.0f);
    for (size_t i = 3; i < maps.rn.size(); i += 11) maps.rn[i] = hf_make_float4(nan, nan, nan, 0.0f);
    {
      for (int step : {1, 2, 3}) {
        for (RobustKernel robust : {RobustKernel::none, RobustKernel::huber, RobustKernel::student_t}) {
          for (int occlusion : {0, 1}) {
            for (double depth_noise_ref_m : {0.0, 2.0}) {  // 2 m: the maps' depths are 1.5-2.5 m, both sides
              RegistrationOptions options = default_registration_options(name);
              options.set("finest_level_photometric_step", step);
              options.set("photometric_occlusion_check", occlusion);
              if (!options.set("depth_noise_ref_m", depth_noise_ref_m) && depth_noise_ref_m > 0.0) continue;
              test::set_robust_kernels(options, robust);
              const MethodProblem mp(maps, name, options);
              if (mp.method.dense == nullptr) GTEST_SKIP() << name << " is not a per-pixel method";
              const ResidualProblem& p = mp.problem;
              if (width == 64 && step == 1 && robust == RobustKernel::none && occlusion == 0) {
                std::printf("%s: %s\n", name.c_str(),
                            simd.vectorises(*p.kernel) ? "AVX2 path" : "no AVX2 path: the pixel loop runs");
              }
              const NormalEquations a = simd.reduce(p), b = scalar.reduce(p);
              SCOPED_TRACE(testing::Message() << width << "x" << height << " " << name << " step " << step
                                              << " robust " << test::robust_name(robust) << " occlusion "
                                              << occlusion << " depth_noise_ref_m " << depth_noise_ref_m);
              ASSERT_GT(b.count, 2);
              EXPECT_EQ(a.count, b.count);
              ASSERT_TRUE(a.JtJ.allFinite() && a.Jtr.allFinite() && std::isfinite(a.cost));
              const double scale = b.JtJ.cwiseAbs().maxCoeff();
              EXPECT_LE((a.JtJ - b.JtJ).cwiseAbs().maxCoeff(), 1e-12 * scale);
              EXPECT_LE((a.Jtr - b.Jtr).cwiseAbs().maxCoeff(), 1e-12 * std::max(1.0, b.Jtr.cwiseAbs().maxCoeff()));
              EXPECT_NEAR(a.cost, b.cost, 1e-12 * std::max(1.0, b.cost));
            }
          }
        }
      }
    }
  }
}

TEST(NormalEquations, SumsRoundTripInDocumentedOrder) {
  std::vector<double> sums(HF_REG_SUMS);
  for (int k = 0; k < HF_REG_SUMS; ++k) sums[size_t(k)] = k + 1;
  const NormalEquations ne = NormalEquations::from_sums(sums.data());
  EXPECT_EQ(ne.JtJ(0, 0), 1.0);
  EXPECT_EQ(ne.JtJ(0, 5), 6.0);
  EXPECT_EQ(ne.JtJ(5, 0), 6.0);
  EXPECT_EQ(ne.JtJ(1, 1), 7.0);
  EXPECT_EQ(ne.JtJ(5, 5), 21.0);
  EXPECT_EQ(ne.Jtr(0), 22.0);
  EXPECT_EQ(ne.cost, 28.0);
  EXPECT_EQ(ne.count, 29);
  EXPECT_EQ(ne.to_sums(), sums);
}

TEST(Kernels, IcpRowMatchesFiniteDifference) {
  // d r / d xi of r(xi) = <v_ref - exp(xi) v, n> at xi = 0 equals J (eq. 24).
  const RandomMaps maps(3);
  RegistrationOptions options = default_registration_options("icp");
  test::set_robust_kernels(options, RobustKernel::none);
  const MethodProblem mp(maps, "icp", options);
  const ResidualProblem& p = mp.problem;
  const hf_reg_maps kernel_maps = p.kernel_maps();
  hf_reg_row row;
  int px = -1;
  for (int x = 10; x < 50 && px < 0; ++x) {
    if (hf_icp_pixel(x, 20, &kernel_maps, p.camera, p.T_ref_cur, *static_cast<const hf_icp_params*>(p.params),
                     &row)) {
      px = x;
    }
  }
  ASSERT_GE(px, 0);
  const SE3 T = SE3::exp((Vector6d() << 0.01, -0.02, 0.005, 0.01, 0.02, -0.01).finished());
  const hf_float4 c = maps.cv[size_t(20 * 64 + px)];
  const Eigen::Vector3d v = T * Eigen::Vector3d(c.x, c.y, c.z);
  // The pair found by the kernel: recover n and v_ref from r and J (J = -[v x n, n]).
  const Eigen::Vector3d n(-row.J[3], -row.J[4], -row.J[5]);
  for (int i = 0; i < 6; ++i) {
    Vector6d d = Vector6d::Zero();
    d(i) = 1e-6;
    const Eigen::Vector3d vp = SE3::exp(d) * v;
    const double dr = -(vp - v).dot(n) / 1e-6;
    EXPECT_NEAR(dr, row.J[i], 1e-4) << i;
  }
}

TEST(Solver, FullRankStepSolvesNormalEquations) {
  Matrix6d A = Matrix6d::Random();
  const Matrix6d H = A * A.transpose() + Matrix6d::Identity();
  const Vector6d g = Vector6d::Random();
  const GaussNewtonStep s = solve_gauss_newton_step(H, g, 1e-6);
  EXPECT_TRUE(s.finite);
  EXPECT_EQ(s.degenerate_dims, 0);
  EXPECT_LT((H * s.xi + g).norm(), 1e-9);
  EXPECT_GT(s.condition_number, 1.0);
}

TEST(Solver, DegenerateDirectionsGetNoUpdate) {
  Matrix6d H = Matrix6d::Zero();
  H.diagonal() << 4.0, 3.0, 2.0, 1e-12, 5.0, 0.0;
  const Vector6d g = Vector6d::Ones();
  const GaussNewtonStep s = solve_gauss_newton_step(H, g, 1e-6);
  EXPECT_TRUE(s.finite);
  EXPECT_EQ(s.degenerate_dims, 2);
  EXPECT_EQ(s.condition_number, 0.0);
  EXPECT_NEAR(s.xi(3), 0.0, 1e-15);
  EXPECT_NEAR(s.xi(5), 0.0, 1e-15);
  EXPECT_NEAR(s.xi(0), -0.25, 1e-12);
  EXPECT_NEAR(s.xi(4), -0.2, 1e-12);
}

TEST(Solver, NonFiniteOrZeroInputIsSafe) {
  Matrix6d H = Matrix6d::Identity();
  H(2, 2) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(solve_gauss_newton_step(H, Vector6d::Zero(), 1e-6).finite);
  const GaussNewtonStep z = solve_gauss_newton_step(Matrix6d::Zero(), Vector6d::Zero(), 1e-6);
  EXPECT_EQ(z.degenerate_dims, 6);
  EXPECT_TRUE(z.xi.allFinite());
  EXPECT_EQ(z.xi.norm(), 0.0);
}

// The outcome rules a method that is not a per-pixel problem (NDT, sparse) reuses: the same statuses by the same
// thresholds as the Gauss-Newton driver.
TEST(Outcome, ClassifyOutcomeAppliesTheSharedRules) {
  const GaussNewtonOptions o;
  NormalEquations ne;
  ne.JtJ = Matrix6d::Identity() * 100.0;
  ne.cost = 2.0;
  ne.count = 1000;
  const GaussNewtonStep full = solve_gauss_newton_step(ne.JtJ, Vector6d::Zero(), o.degeneracy_threshold);
  const SE3 T0;
  const SE3 T = SE3::exp((Vector6d() << 0.0, 0.01, 0.0, 0.02, 0.0, 0.0).finished());
  RegistrationResult r;
  ASSERT_TRUE(classify_outcome(o, ne, full, 2000.0, T0, T, Vector6d::Zero(), r));
  EXPECT_EQ(r.status, RegistrationStatus::good);
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, T), 1e-15);
  EXPECT_DOUBLE_EQ(r.inlier_ratio, 0.5);
  EXPECT_DOUBLE_EQ(r.final_cost, 0.002);
  classify_outcome(o, ne, full, 1e4, T0, T, Vector6d::Zero(), r);  // 10 % of the possible rows
  EXPECT_EQ(r.status, RegistrationStatus::poor);
  GaussNewtonStep flat = full;
  flat.degenerate_dims = 2;
  classify_outcome(o, ne, flat, 2000.0, T0, T, Vector6d::Zero(), r);
  EXPECT_EQ(r.status, RegistrationStatus::degenerate);
  const SE3 far = SE3::exp((Vector6d() << 0.0, 0.0, 0.0, 0.6, 0.0, 0.0).finished());  // beyond max_translation_m
  classify_outcome(o, ne, full, 2000.0, T0, far, Vector6d::Zero(), r);
  EXPECT_EQ(r.status, RegistrationStatus::failed);
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, T0), 1e-15);  // never a wild pose
  classify_outcome(o, ne, full, 2000.0, T0, T, Vector6d::Constant(0.01), r);  // still sliding
  EXPECT_EQ(r.status, RegistrationStatus::failed);
  ne.cost = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(classify_outcome(o, ne, full, 2000.0, T0, T, Vector6d::Zero(), r));
  EXPECT_EQ(r.status, RegistrationStatus::failed);
  test::expect_finite(r);
}

TEST(Outcome, LargeMotionsNeedTheReverseAlignmentToAgree) {
  const GaussNewtonOptions o;
  const SE3 T0;
  const SE3 big = SE3::exp((Vector6d() << 0.0, 0.0, 0.0, 0.08, 0.0, 0.0).finished());  // > verify_motion_m
  RegistrationResult r;
  r.status = RegistrationStatus::good;
  r.T_ref_cur = big;
  int reverse_calls = 0;
  auto reverse_agrees = [&](const SE3&) {
    ++reverse_calls;
    RegistrationResult rev;
    rev.status = RegistrationStatus::good;
    rev.T_ref_cur = big.inverse();
    return rev;
  };
  verify_large_motion(o, T0, reverse_agrees, r);
  EXPECT_EQ(r.status, RegistrationStatus::good);
  EXPECT_EQ(reverse_calls, 1);
  auto reverse_disagrees = [&](const SE3&) {
    RegistrationResult rev;
    rev.status = RegistrationStatus::good;
    rev.T_ref_cur = SE3();
    return rev;
  };
  verify_large_motion(o, T0, reverse_disagrees, r);
  EXPECT_EQ(r.status, RegistrationStatus::failed);
  EXPECT_LT(test::translation_error_m(r.T_ref_cur, T0), 1e-15);
  // A small motion is not re-checked.
  RegistrationResult small;
  small.status = RegistrationStatus::good;
  small.T_ref_cur = SE3::exp((Vector6d() << 0.0, 0.0, 0.0, 0.01, 0.0, 0.0).finished());
  reverse_calls = 0;
  verify_large_motion(o, T0, reverse_agrees, small);
  EXPECT_EQ(reverse_calls, 0);
  EXPECT_EQ(small.status, RegistrationStatus::good);
}

TEST(Registry, NamesAndErrors) {
  // Sorted, with every built-in per-pixel method (helpers may add more lines to methods.def).
  const std::vector<std::string> names = registration_names();
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  for (const char* builtin : {"combined", "gicp", "icp", "photometric"})
    EXPECT_NE(std::find(names.begin(), names.end(), builtin), names.end()) << builtin;
  std::string known;
  for (const std::string& name : names) known += (known.empty() ? "" : ", ") + name;
  for (const std::string& name : registration_names()) {
    auto reg = make_registration(name);
    EXPECT_EQ(reg->name(), name);
  }
  try {
    make_registration("nope");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("known: " + known + ")"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make_backend("cuda"), Error);
  EXPECT_EQ(make_backend("cpu")->name(), "cpu");
  RegistrationOptions bad = default_registration_options("icp");
  bad.method_as<IcpOptions>().max_dist_m = -1.0f;
  EXPECT_THROW(make_registration("icp", bad, make_backend("cpu")), Error);
  // Options of another method, or none, are an error naming the mix-up, not a crash.
  EXPECT_THROW(make_registration("icp", default_registration_options("photometric"), make_backend("cpu")), Error);
  EXPECT_THROW(make_registration("icp", RegistrationOptions(), make_backend("cpu")), Error);
}

// Each method owns its knobs; the driver's are shared. Every key appears once in a method's flat namespace (so a
// JSON object of them is unambiguous), set() reaches it, and a copy is deep.
TEST(Options, EveryKeyOnceSetReachesItCopiesAreDeep) {
  for (const std::string& name : registration_names()) {
    RegistrationOptions o = default_registration_options(name);
    std::vector<std::string> keys;
    o.for_each_option([&keys](const char* k, auto&) { keys.emplace_back(k); });
    std::vector<std::string> sorted = keys;
    std::sort(sorted.begin(), sorted.end());
    EXPECT_EQ(std::adjacent_find(sorted.begin(), sorted.end()), sorted.end()) << name << ": a key appears twice";
    EXPECT_NE(std::find(keys.begin(), keys.end(), "iterations"), keys.end()) << name;
    EXPECT_NO_THROW(o.validate());
    EXPECT_TRUE(o.set("degeneracy_threshold", 0.25));
    EXPECT_EQ(o.driver.degeneracy_threshold, 0.25);
    EXPECT_FALSE(o.set("no_such_knob", 1.0));
    const RegistrationOptions copy = o;
    EXPECT_NE(copy.method(), o.method());
  }
  RegistrationOptions combined = default_registration_options("combined");
  EXPECT_TRUE(combined.set("rgb_weight", 0.4));
  EXPECT_FLOAT_EQ(combined.method_as<CombinedOptions>().rgb_weight, 0.4f);
  RegistrationOptions icp = default_registration_options("icp");
  EXPECT_FALSE(icp.set("rgb_weight", 0.4));  // icp has no photometric term
  EXPECT_THROW(icp.method_as<CombinedOptions>(), Error);
}

// report.json files written before methods owned their knobs hold every method's keys in one object.
TEST(Options, FormerKeysMigrateByTheDocumentedRules) {
  const RegistrationOptions icp = default_registration_options("icp");
  const RegistrationOptions photometric = default_registration_options("photometric");
  const RegistrationOptions combined = default_registration_options("combined");
  using Key = std::optional<std::string>;
  EXPECT_EQ(migrate_registration_key(icp, "max_dist_m"), Key("max_dist_m"));
  EXPECT_EQ(migrate_registration_key(icp, "t_dof"), Key("t_dof_icp"));
  EXPECT_EQ(migrate_registration_key(icp, "rgb_weight"), Key(""));
  EXPECT_EQ(migrate_registration_key(icp, "huber_rgb"), Key(""));
  EXPECT_EQ(migrate_registration_key(photometric, "max_dist_m"), Key("occlusion_max_depth_m"));
  EXPECT_EQ(migrate_registration_key(photometric, "t_dof"), Key("t_dof"));
  EXPECT_EQ(migrate_registration_key(photometric, "huber_icp_m"), Key(""));
  EXPECT_EQ(migrate_registration_key(combined, "rgb_weight"), Key("rgb_weight"));
  EXPECT_EQ(migrate_registration_key(combined, "t_dof"), Key("t_dof"));
  EXPECT_EQ(migrate_registration_key(combined, "max_dist_m"), Key("max_dist_m"));
  // The driver alone (no method: the pipeline's groundtruth) keeps the driver's keys and drops the rest.
  EXPECT_EQ(migrate_registration_key(RegistrationOptions(), "iterations"), Key("iterations"));
  EXPECT_EQ(migrate_registration_key(RegistrationOptions(), "robust_icp"), Key(""));
  EXPECT_EQ(migrate_registration_key(icp, "voxel"), std::nullopt);  // never a registration option
}

TEST(Problem, MissingMapIsAnErrorNotACrash) {
  const RandomMaps maps(1);
  MethodProblem mp(maps, "combined");
  ResidualProblem p = mp.problem;
  p.maps[HF_REG_IN_REF_GRAD_Y] = {};
  CpuReductionBackend backend;
  try {
    backend.reduce(p);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("ref_grad_y is missing"), std::string::npos) << e.what();
  }
  p = mp.problem;
  p.kernel = nullptr;
  EXPECT_THROW(backend.reduce(p), Error);
}

}  // namespace
}  // namespace hf
