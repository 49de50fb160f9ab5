// A method is its own files plus one registration line: a throwaway ICP with the symmetric point-to-plane objective
// (Rusinkiewicz 2019: the residual along the sum of both normals), written only here, registered at run time, runs
// on every backend through the generic driver, reduction and backends without a line of them knowing it. It has no
// AVX2 spelling, so the vectorised cpu backend must run its pixel loop (never zero rows), and it brings its OpenCL
// source (DenseKernel::opencl_source).
//
// Why not point-to-point rows (the first choice): with projective association the reference point lies on the
// current point's viewing ray, so v_ref - v only measures the offset along the ray and the motion across it stays
// at the guess (tried here: 9.9 mm error on a 9.9 mm motion, status good). Any residual that can see the surface's
// orientation works; the symmetric one is the smallest that is not the shipped icp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "reg_test_util.h"
#include "registration/cpu_backend.h"
#include "registration/dense_method.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

// The kernel, written once: compiled here as C++, and its text (the macro's argument, stringified before any
// expansion) is the OpenCL source. One row per pixel: r = <v_ref - v, n_s> with n_s = n_ref + R n_cur, linearised
// with n_s held fixed: J = -[ (v x n_s)^T n_s^T ].
#define HF_TEST_KERNEL(...) \
  __VA_ARGS__               \
  const char* const kSymmetricSource = #__VA_ARGS__;
HF_TEST_KERNEL(
typedef struct { float max_dist_m; float min_normal_cos; } hf_symmetric_params;

HF_INLINE int hf_symmetric_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T,
                                 hf_symmetric_params p, hf_reg_row* rows) {
  const int idx = y * K.width + x;
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[idx];
  const hf_float4 nc = hf_reg_map4(maps, HF_REG_IN_CUR_NORMALS)[idx];
  if (!hf_is_valid4(vc) || !hf_is_valid4(nc)) return 0;
  hf_float4 v;
  const int ridx = hf_reg_associate_nearest(vc, K, T, &v);
  if (ridx < 0) return 0;
  const hf_float4 vr = hf_reg_map4(maps, HF_REG_IN_REF_VERTICES)[ridx];
  const hf_float4 nr = hf_reg_map4(maps, HF_REG_IN_REF_NORMALS)[ridx];
  if (!hf_is_valid4(vr) || !hf_is_valid4(nr)) return 0;
  const hf_float4 d = hf_sub3(vr, v);
  const hf_float4 n = hf_reg_rotate(T, nc);
  if (!(hf_dot3(d, d) <= p.max_dist_m * p.max_dist_m) || !(hf_dot3(n, nr) >= p.min_normal_cos)) return 0;
  const hf_float4 ns = hf_make_float4(nr.x + n.x, nr.y + n.y, nr.z + n.z, 0.0f);
  hf_reg_set_row(v, hf_scale3(ns, -1.0f), hf_dot3(d, ns), 1.0f, rows);
  return 1;
}

HF_REG_OPENCL_KERNEL(symmetric_test, hf_symmetric_pixel, hf_symmetric_params)
)

// Its own options.
struct SymmetricOptions : MethodOptionsBase<SymmetricOptions> {
  float max_dist_m = 0.1f;
  float min_normal_cos = 0.866f;  // 30 degrees
  void visit(OptionVisitor& v) override {
    v("max_dist_m", max_dist_m);
    v("min_normal_cos", min_normal_cos);
  }
  void validate() const override {
    require_option(finite_positive(max_dist_m), "max_dist_m must be finite and > 0");
  }
};

constexpr unsigned kInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_NORMALS) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_REF_NORMALS);
const DenseKernel kSymmetricKernel = make_dense_kernel<hf_symmetric_params, hf_symmetric_pixel>(
    "symmetric_test", kInputs, 1, nullptr, kSymmetricSource);

class SymmetricMethod final : public DenseMethod {
 public:
  explicit SymmetricMethod(const SymmetricOptions& o) : params_{o.max_dist_m, o.min_normal_cos} {}
  const DenseKernel& kernel() const override { return kSymmetricKernel; }
  void begin_level(int, const FramePyramidLevel&, const FramePyramidLevel&, ResidualProblem&) override {}
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices));
  }

 private:
  hf_symmetric_params params_;
};

// The one registration line (a built-in method's is its line in registration/methods.def).
const RegistrationMethod kSymmetric{
    "symmetric_test", [] { return RegistrationOptions(GaussNewtonOptions{}, std::make_unique<SymmetricOptions>()); },
    [](const RegistrationOptions& o, std::unique_ptr<ReductionBackend> b) -> std::unique_ptr<Registration> {
      return std::make_unique<GaussNewtonRegistration>(
          "symmetric_test", std::make_unique<SymmetricMethod>(o.method_as<SymmetricOptions>()), o, std::move(b));
    }};

class Plugin : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { register_registration(kSymmetric); }
};

TEST_F(Plugin, IsRegisteredByName) {
  const std::vector<std::string> names = registration_names();
  EXPECT_NE(std::find(names.begin(), names.end(), "symmetric_test"), names.end());
  EXPECT_TRUE(std::is_sorted(names.begin(), names.end()));
  EXPECT_THROW(register_registration(kSymmetric), Error);  // a name is registered once
  EXPECT_EQ(make_registration("symmetric_test")->name(), "symmetric_test");
}

// On the noise-free room pair every backend recovers the motion and gives the same answer: the bound of the shipped
// icp on the same pair (tests/registration/test_accuracy.cpp, 0.5 mm / 0.02 deg), as the two residuals see the
// same surfaces through the same association.
TEST_F(Plugin, RecoversTheMotionOnEveryBackend) {
  const test::FramePair pair = test::make_pair("room", 10, 11, false, 3, /*bilateral=*/false);
  std::vector<std::pair<std::string, std::unique_ptr<ReductionBackend>>> backends;
  backends.emplace_back("cpu", std::make_unique<CpuReductionBackend>());
  backends.emplace_back("cpu-scalar", std::make_unique<CpuReductionBackend>(8, false));
  try {
    backends.emplace_back("opencl", make_backend("opencl"));
  } catch (const Error& e) {
    std::printf("opencl skipped: %s\n", e.what());
  }
  std::optional<SE3> first;
  for (auto& [name, backend] : backends) {
    const RegistrationResult r =
        make_registration("symmetric_test", default_registration_options("symmetric_test"), std::move(backend))
            ->align(pair.current, pair.reference, SE3());
    test::expect_finite(r);
    const double et = test::translation_error_m(r.T_ref_cur, pair.T_ref_cur_true);
    const double er = test::rotation_error_deg(r.T_ref_cur, pair.T_ref_cur_true);
    std::printf("symmetric_test/%s: %s, error %.3f mm %.4f deg, %ld rows\n", name.c_str(), to_string(r.status),
                et * 1e3, er, r.inliers);
    EXPECT_TRUE(r.usable()) << name << ": " << r.message;
    EXPECT_GT(r.inliers, 10000) << name;
    EXPECT_LT(et, 0.5e-3) << name;
    EXPECT_LT(er, 0.02) << name;
    if (!first) {
      first = r.T_ref_cur;
    } else {
      EXPECT_LT(test::translation_error_m(r.T_ref_cur, *first), 1e-6) << name;
      EXPECT_LT(test::rotation_error_deg(r.T_ref_cur, *first), 1e-4) << name;
    }
  }
}

}  // namespace
}  // namespace hf
