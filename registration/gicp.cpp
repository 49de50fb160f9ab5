#include "registration/gicp.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/parallel.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

constexpr unsigned kGicpInputs =
    HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_NORMALS) | HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) |
    HF_REG_IN_BIT(HF_REG_IN_REF_NORMALS) | HF_REG_IN_BIT(HF_REG_IN_GICP_CUR_COV_A) |
    HF_REG_IN_BIT(HF_REG_IN_GICP_CUR_COV_B) | HF_REG_IN_BIT(HF_REG_IN_GICP_REF_COV_A) |
    HF_REG_IN_BIT(HF_REG_IN_GICP_REF_COV_B);
const DenseKernel kGicpKernel = make_dense_kernel<hf_gicp_params, hf_gicp_pixel>("gicp", kGicpInputs, 3);

// The regularised covariance of pixel (x, y), or false: mean and scatter of the gated window, then Segal's
// U diag(epsilon, 1, 1) U^T in the scatter's eigenbasis (eigenvalues ascending: the normal first).
bool pixel_covariance(const VertexMap& vertices, int x, int y, float gate_px_m, const GicpOptions& o,
                      Eigen::Matrix3f* C) {
  const hf_float4 c = vertices(x, y);
  if (c.w == 0.0f) return false;
  const int r = o.gicp_window_px;
  const float gate = gate_px_m * c.z, gate_sq = gate * gate;
  // Sums relative to the centre (no cancellation of metres-sized coordinates): a few centimetres, so float
  // keeps ~1e-9 m^2 of the scatter, far below the sensor's noise.
  float sx = 0, sy = 0, sz = 0, xx = 0, xy = 0, xz = 0, yy = 0, yz = 0, zz = 0;
  int n = 0;
  const int v0 = std::max(0, y - r), v1 = std::min(vertices.height() - 1, y + r);
  const int u0 = std::max(0, x - r), u1 = std::min(vertices.width() - 1, x + r);
  for (int v = v0; v <= v1; ++v) {
    const hf_float4* row = &vertices(0, v);
    for (int u = u0; u <= u1; ++u) {
      const hf_float4 q = row[u];
      const float dx = q.x - c.x, dy = q.y - c.y, dz = q.z - c.z;
      if (q.w == 0.0f || !(dx * dx + dy * dy + dz * dz <= gate_sq)) continue;
      sx += dx, sy += dy, sz += dz;
      xx += dx * dx, xy += dx * dy, xz += dx * dz, yy += dy * dy, yz += dy * dz, zz += dz * dz;
      ++n;
    }
  }
  if (n < o.gicp_min_neighbours) return false;
  const float inv = 1.0f / float(n);
  const float mx = sx * inv, my = sy * inv, mz = sz * inv;
  Eigen::Matrix3f cov;
  cov(0, 0) = xx * inv - mx * mx;
  cov(0, 1) = cov(1, 0) = xy * inv - mx * my;
  cov(0, 2) = cov(2, 0) = xz * inv - mx * mz;
  cov(1, 1) = yy * inv - my * my;
  cov(1, 2) = cov(2, 1) = yz * inv - my * mz;
  cov(2, 2) = zz * inv - mz * mz;
  // Closed-form 3x3 eigen-decomposition (eigenvalues ascending: the normal first).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3f> eig;
  eig.computeDirect(cov);
  const Eigen::Vector3f ev = eig.eigenvalues();
  if (!(ev(2) > 0.0f) || !(ev(1) >= 1e-2f * ev(2))) return false;  // a line or a single point: no plane
  // Segal's U diag(epsilon, 1, 1) U^T = I - (1 - epsilon) n n^T.
  const Eigen::Vector3f normal = eig.eigenvectors().col(0);
  *C = Eigen::Matrix3f::Identity() - (1.0f - o.gicp_epsilon) * normal * normal.transpose();
  return C->allFinite();
}

class GicpMethod final : public DenseMethod {
 public:
  explicit GicpMethod(const GicpOptions& options) : options_(options), params_(options.kernel_params()) {}
  const DenseKernel& kernel() const override { return kGicpKernel; }
  void begin_level(int level, const FramePyramidLevel& current, const FramePyramidLevel& reference,
                   ResidualProblem& problem) override {
    params_.step = level == 0 ? options_.finest_level_gicp_step : 1;
    gicp_covariances(current.vertices, current.camera, options_, &cur_a_, &cur_b_, params_.step);
    gicp_covariances(reference.vertices, reference.camera, options_, &ref_a_, &ref_b_);
    problem.set_map(HF_REG_IN_GICP_CUR_COV_A, cur_a_.data());
    problem.set_map(HF_REG_IN_GICP_CUR_COV_B, cur_b_.data());
    problem.set_map(HF_REG_IN_GICP_REF_COV_A, ref_a_.data());
    problem.set_map(HF_REG_IN_GICP_REF_COV_B, ref_b_.data());
  }
  const void* params() const override { return &params_; }
  int pixel_step() const override { return std::max(1, params_.step); }
  // Three rows per valid current pixel of the finest level's grid.
  double rows_possible(const FramePyramidLevel& current) const override {
    return 3.0 * double(count_valid_pixels(current.vertices, std::max(1, options_.finest_level_gicp_step)));
  }

 private:
  GicpOptions options_;
  hf_gicp_params params_;
  std::vector<hf_float4> cur_a_, cur_b_, ref_a_, ref_b_;
};

RegistrationOptions gicp_defaults() { return RegistrationOptions(GaussNewtonOptions{}, std::make_unique<GicpOptions>()); }

std::unique_ptr<Registration> make_gicp(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "gicp", std::make_unique<GicpMethod>(options.method_as<GicpOptions>()), options, std::move(backend));
}

}  // namespace

void gicp_covariances(const VertexMap& vertices, const PinholeCamera& camera, const GicpOptions& options,
                      std::vector<hf_float4>* a, std::vector<hf_float4>* b, int step) {
  step = std::max(1, step);
  const int w = vertices.width(), h = vertices.height();
  a->assign(size_t(w) * size_t(h), hf_invalid4());
  b->assign(size_t(w) * size_t(h), hf_invalid4());
  // The window's footprint per metre of depth, times the gate factor.
  const float gate_px_m = options.gicp_neighbour_gate * float(options.gicp_window_px) / float(camera.fx);
  parallel_for_rows(h, [&](int y) {
    if (y % step != 0) return;
    for (int x = 0; x < w; x += step) {
      Eigen::Matrix3f C;
      if (!pixel_covariance(vertices, x, y, gate_px_m, options, &C)) continue;
      const size_t i = size_t(y) * size_t(w) + size_t(x);
      (*a)[i] = hf_make_float4(C(0, 0), C(0, 1), C(0, 2), C(1, 1));
      (*b)[i] = hf_make_float4(C(1, 2), C(2, 2), 0.0f, 1.0f);
    }
  });
}

void GicpOptions::visit(OptionVisitor& v) {
  v("max_dist_m", max_dist_m);
  v("max_normal_angle_deg", max_normal_angle_deg);
  v("gicp_epsilon", gicp_epsilon);
  v("gicp_window_px", gicp_window_px);
  v("gicp_neighbour_gate", gicp_neighbour_gate);
  v("gicp_min_neighbours", gicp_min_neighbours);
  v("finest_level_gicp_step", finest_level_gicp_step);
  v("robust_gicp", robust_gicp);
  v("huber_gicp_m", huber_gicp_m);
  v("t_sigma_gicp_m", t_sigma_gicp_m);
  v("t_dof_gicp", t_dof_gicp);
}

void GicpOptions::validate() const {
  require_option(finite_positive(max_dist_m), "max_dist_m must be finite and > 0");
  require_option(std::isfinite(max_normal_angle_deg) && max_normal_angle_deg > 0.0f && max_normal_angle_deg <= 180.0f,
                 "max_normal_angle_deg must be in (0, 180]");
  require_option(std::isfinite(gicp_epsilon) && gicp_epsilon >= 1e-6f && gicp_epsilon <= 1.0f,
                 "gicp_epsilon must be in [1e-6, 1]");
  require_option(gicp_window_px >= 1 && gicp_window_px <= 8, "gicp_window_px must be in 1..8");
  require_option(finite_positive(gicp_neighbour_gate), "gicp_neighbour_gate must be finite and > 0");
  require_option(gicp_min_neighbours >= 3 && gicp_min_neighbours <= (2 * gicp_window_px + 1) * (2 * gicp_window_px + 1),
                 "gicp_min_neighbours must be in 3..(2 gicp_window_px + 1)^2");
  require_option(finest_level_gicp_step >= 1 && finest_level_gicp_step <= 16, "finest_level_gicp_step must be in 1..16");
  require_option(finite_positive(huber_gicp_m), "huber_gicp_m must be finite and > 0");
  require_option(finite_positive(t_sigma_gicp_m), "t_sigma_gicp_m must be finite and > 0");
  require_option(finite_positive(t_dof_gicp), "t_dof_gicp must be finite and > 0");
}

hf_gicp_params GicpOptions::kernel_params() const {
  hf_gicp_params p{};
  p.max_dist_m = max_dist_m;
  p.min_normal_cos = float(std::cos(double(max_normal_angle_deg) * std::numbers::pi / 180.0));
  p.weight = 1.0f;
  p.residual_scale = std::sqrt(2.0f * gicp_epsilon);
  p.robust = robust_params(robust_gicp, huber_gicp_m, t_sigma_gicp_m, t_dof_gicp);
  p.step = 1;
  return p;
}

RegistrationMethod gicp_registration_method() { return {"gicp", gicp_defaults, make_gicp}; }

}  // namespace hf
