#include "registration/icp.h"

#include <cmath>
#include <numbers>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

constexpr unsigned kIcpInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_NORMALS) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_REF_NORMALS);
const DenseKernel kIcpKernel = make_dense_kernel<hf_icp_params, hf_icp_pixel>("icp", kIcpInputs, 1, &detail::icp_rows_avx2);

class IcpMethod final : public DenseMethod {
 public:
  explicit IcpMethod(const IcpOptions& options) : params_(options.kernel_params()) {}
  const DenseKernel& kernel() const override { return kIcpKernel; }
  void begin_level(int, const FramePyramidLevel&, const FramePyramidLevel&, ResidualProblem&) override {}
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices));
  }

 private:
  hf_icp_params params_;
};

RegistrationOptions icp_defaults() { return RegistrationOptions(GaussNewtonOptions{}, std::make_unique<IcpOptions>()); }

std::unique_ptr<Registration> make_icp(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "icp", std::make_unique<IcpMethod>(options.method_as<IcpOptions>()), options, std::move(backend));
}

}  // namespace

void IcpOptions::visit(OptionVisitor& v) {
  v("max_dist_m", max_dist_m);
  v("max_normal_angle_deg", max_normal_angle_deg);
  v("robust_icp", robust_icp);
  v("huber_icp_m", huber_icp_m);
  v("t_sigma_icp_m", t_sigma_icp_m);
  v("t_dof_icp", t_dof_icp);
  v("depth_noise_ref_m", depth_noise_ref_m);
}

void IcpOptions::validate() const {
  require_option(finite_positive(max_dist_m), "max_dist_m must be finite and > 0");
  require_option(std::isfinite(max_normal_angle_deg) && max_normal_angle_deg > 0.0f && max_normal_angle_deg <= 180.0f,
                 "max_normal_angle_deg must be in (0, 180]");
  require_option(finite_positive(huber_icp_m), "huber_icp_m must be finite and > 0");
  require_option(finite_positive(t_sigma_icp_m), "t_sigma_icp_m must be finite and > 0");
  require_option(finite_positive(t_dof_icp), "t_dof_icp must be finite and > 0");
  require_option(std::isfinite(depth_noise_ref_m) && depth_noise_ref_m >= 0.0f,
                 "depth_noise_ref_m must be finite and >= 0");
}

hf_icp_params IcpOptions::kernel_params(float weight) const {
  hf_icp_params p{};
  p.max_dist_m = max_dist_m;
  p.min_normal_cos = float(std::cos(double(max_normal_angle_deg) * std::numbers::pi / 180.0));
  p.weight = weight;
  p.robust = robust_params(robust_icp, huber_icp_m, t_sigma_icp_m, t_dof_icp);
  p.depth_noise_ref_m = depth_noise_ref_m;
  return p;
}

const DenseKernel& icp_kernel() { return kIcpKernel; }

RegistrationMethod icp_registration_method() { return {"icp", icp_defaults, make_icp}; }

}  // namespace hf
