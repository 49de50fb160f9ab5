#include "registration/combined.h"

#include <cmath>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/combined_kernel.h"

namespace hf {
namespace {

constexpr unsigned kInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_NORMALS) |
                             HF_REG_IN_BIT(HF_REG_IN_CUR_INTENSITY) | HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_NORMALS) | HF_REG_IN_BIT(HF_REG_IN_REF_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_X) | HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_Y);
const DenseKernel kKernel = make_dense_kernel<hf_combined_params, hf_combined_pixel>(
    "combined", kInputs, 2, &detail::combined_rows_avx2);

class CombinedMethod final : public DenseMethod {
 public:
  explicit CombinedMethod(const CombinedOptions& options) : options_(options) {}
  const DenseKernel& kernel() const override { return kKernel; }
  void begin_level(int level, const FramePyramidLevel&, const FramePyramidLevel&, ResidualProblem&) override {
    params_.icp = options_.icp.kernel_params();
    params_.photometric =
        options_.photometric.kernel_params(level, options_.rgb_weight, options_.photometric.t_sigma_rgb_init);
  }
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices)) + options_.photometric.rows_possible(current);
  }

 private:
  CombinedOptions options_;
  hf_combined_params params_{};
};

RegistrationOptions defaults() {
  return RegistrationOptions(GaussNewtonOptions{}, std::make_unique<CombinedOptions>());
}

std::unique_ptr<Registration> make(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "combined", std::make_unique<CombinedMethod>(options.method_as<CombinedOptions>()), options, std::move(backend));
}

}  // namespace

void CombinedOptions::visit(OptionVisitor& v) {
  icp.visit(v);
  photometric.visit(v);
  v("rgb_weight", rgb_weight);
}

void CombinedOptions::validate() const {
  icp.validate();
  photometric.validate();
  require_option(std::isfinite(rgb_weight) && rgb_weight >= 0.0f, "rgb_weight must be finite and >= 0");
}

RegistrationMethod combined_registration_method() { return {"combined", defaults, make}; }

}  // namespace hf
