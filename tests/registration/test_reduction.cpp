// The reduction contract: the 29 sums, the cpu backend against a naive double sum of the same rows, the
// degeneracy-aware solve, and the registries.
#include <gtest/gtest.h>

#include <limits>
#include <random>

#include "core/error.h"
#include "registration/cpu_backend.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/residuals.h"
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

  ResidualProblem problem(int method) const {
    ResidualProblem p;
    p.camera = K;
    p.cur_vertices = cv.data();
    p.cur_normals = cn.data();
    p.cur_intensity = ci.data();
    p.ref_vertices = rv.data();
    p.ref_normals = rn.data();
    p.ref_intensity = ri.data();
    p.ref_grad_x = gx.data();
    p.ref_grad_y = gy.data();
    p.T_ref_cur = to_transform12(SE3::exp((Vector6d() << 0.01, -0.02, 0.005, 0.01, 0.02, -0.01).finished()));
    p.params.method = method;
    p.params.max_dist_m = 0.1f;
    p.params.min_normal_cos = 0.5f;
    p.params.icp_weight = 1.0f;
    p.params.rgb_weight = 0.3f;
    p.params.robust_icp = HF_ROBUST_HUBER;
    p.params.scale_icp = 0.01f;
    p.params.robust_rgb = HF_ROBUST_STUDENT_T;
    p.params.scale_rgb = 0.05f;
    p.params.t_dof = 5.0f;
    p.params.occlusion_check = 1;
    return p;
  }
};

// The naive reference: every row of every pixel, in pixel order, in one double sum written out longhand.
NormalEquations naive_sum(const ResidualProblem& p) {
  NormalEquations ne;
  for (int y = 0; y < p.height(); ++y) {
    for (int x = 0; x < p.width(); ++x) {
      hf_reg_row rows[HF_REG_MAX_ROWS];
      const int n = hf_reg_pixel(x, y, p.cur_vertices, p.cur_normals, p.cur_intensity, p.ref_vertices,
                                 p.ref_normals, p.ref_intensity, p.ref_grad_x, p.ref_grad_y, p.camera, p.T_ref_cur,
                                 p.params, rows);
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

class CpuBackend : public ::testing::TestWithParam<int> {};

TEST_P(CpuBackend, EqualsNaiveDoubleSum) {
  const RandomMaps maps(7);
  const ResidualProblem p = maps.problem(GetParam());
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
  const ResidualProblem p = maps.problem(GetParam());
  CpuReductionBackend a(8);
  const NormalEquations x = a.reduce(p), y = a.reduce(p);
  // Same chunking: bit-identical whatever the thread scheduling.
  EXPECT_EQ(x.to_sums(), y.to_sums());
}

INSTANTIATE_TEST_SUITE_P(Methods, CpuBackend, ::testing::Values(HF_REG_ICP, HF_REG_PHOTOMETRIC, HF_REG_COMBINED));

// The AVX2 path (registration/cpu_backend_avx2.h) evaluates the scalar kernel's rows bit for bit, so against the
// pixel-by-pixel loop only the order of the double sums differs: agreement to 1e-12 relative. Covered: widths
// that are and are not multiples of the eight lanes, photometric grids 1-3, every robust kernel, and invalid
// pixels whose other fields are NaN (the lanes' masks must keep them out, as the scalar kernel's early returns do).
TEST(CpuBackendAvx2, SameRowsAsThePixelLoop) {
  CpuReductionBackend simd(5, true), scalar(5, false);
  if (!simd.vectorised()) GTEST_SKIP() << "this processor has no AVX2: only the pixel loop runs here";
  EXPECT_FALSE(scalar.vectorised());
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (const auto& [width, height] : {std::pair{64, 48}, std::pair{61, 47}, std::pair{13, 9}}) {
    RandomMaps maps(21, width, height);
    for (size_t i = 0; i < maps.cv.size(); i += 5) maps.cv[i] = hf_make_float4(nan, nan, nan, 0.0f);
    for (size_t i = 2; i < maps.rv.size(); i += 7) maps.rv[i] = hf_make_float4(nan, nan, nan, 0.0f);
    for (size_t i = 3; i < maps.rn.size(); i += 11) maps.rn[i] = hf_make_float4(nan, nan, nan, 0.0f);
    for (int method : {HF_REG_ICP, HF_REG_PHOTOMETRIC, HF_REG_COMBINED}) {
      for (int step : {1, 2, 3}) {
        for (int robust : {HF_ROBUST_NONE, HF_ROBUST_HUBER, HF_ROBUST_STUDENT_T}) {
          for (int occlusion : {0, 1}) {
            ResidualProblem p = maps.problem(method);
            p.params.photometric_step = step;
            p.params.robust_icp = p.params.robust_rgb = robust;
            p.params.occlusion_check = occlusion;
            const NormalEquations a = simd.reduce(p), b = scalar.reduce(p);
            SCOPED_TRACE(testing::Message() << width << "x" << height << " method " << method << " step " << step
                                            << " robust " << robust << " occlusion " << occlusion);
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
  ResidualProblem p = maps.problem(HF_REG_ICP);
  p.params.robust_icp = HF_ROBUST_NONE;
  hf_reg_row row;
  int px = -1;
  for (int x = 10; x < 50 && px < 0; ++x) {
    if (hf_icp_pixel(x, 20, p.cur_vertices, p.cur_normals, p.ref_vertices, p.ref_normals, p.camera, p.T_ref_cur,
                     p.params, &row)) {
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

TEST(Registry, NamesAndErrors) {
  EXPECT_EQ(registration_names(), (std::vector<std::string>{"combined", "icp", "photometric"}));
  for (const std::string& name : registration_names()) {
    auto reg = make_registration(name);
    EXPECT_EQ(reg->name(), name);
  }
  try {
    make_registration("nope");
    FAIL();
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("known: combined, icp, photometric"), std::string::npos) << e.what();
  }
  EXPECT_THROW(make_backend("cuda"), Error);
  EXPECT_EQ(make_backend("cpu")->name(), "cpu");
  RegistrationOptions bad;
  bad.max_dist_m = -1.0f;
  EXPECT_THROW(make_registration("icp", bad, make_backend("cpu")), Error);
}

TEST(Problem, MissingMapIsAnErrorNotACrash) {
  const RandomMaps maps(1);
  ResidualProblem p = maps.problem(HF_REG_COMBINED);
  p.ref_grad_y = nullptr;
  CpuReductionBackend backend;
  EXPECT_THROW(backend.reduce(p), Error);
}

}  // namespace
}  // namespace hf
