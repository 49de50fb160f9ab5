#include "registration/photometric.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

constexpr unsigned kInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_REF_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_X) | HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_Y);
const DenseKernel kKernel = make_dense_kernel<hf_photometric_params, hf_photometric_pixel>(
    "photometric", kInputs, 1, &detail::photometric_rows_avx2);

class PhotometricMethod final : public DenseMethod {
 public:
  explicit PhotometricMethod(const PhotometricOptions& options) : options_(options) {}
  const DenseKernel& kernel() const override { return kKernel; }
  void begin_level(int level, const FramePyramidLevel&, const FramePyramidLevel&, ResidualProblem&) override {
    params_ = options_.kernel_params(level, 1.0f, options_.t_sigma_rgb_init);
  }
  const void* params() const override { return &params_; }
  int pixel_step() const override { return std::max(1, params_.step); }
  // DVO: sigma^2 = 1/n sum r^2 (nu + 1) / (nu + r^2 / sigma^2), i.e. cost / count under the current weights.
  void end_iteration(const NormalEquations& ne) override {
    if (options_.robust_rgb != RobustKernel::student_t || ne.count <= 0) return;
    params_.robust.scale = std::max(options_.t_sigma_rgb_min, float(std::sqrt(ne.cost / double(ne.count))));
  }
  double rows_possible(const FramePyramidLevel& current) const override { return options_.rows_possible(current); }

 private:
  PhotometricOptions options_;
  hf_photometric_params params_{};
};

RegistrationOptions defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {20, 10, 10};
  return RegistrationOptions(driver, std::make_unique<PhotometricOptions>());
}

std::unique_ptr<Registration> make(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "photometric", std::make_unique<PhotometricMethod>(options.method_as<PhotometricOptions>()), options,
      std::move(backend));
}

}  // namespace

void PhotometricOptions::visit(OptionVisitor& v) {
  v("robust_rgb", robust_rgb);
  v("huber_rgb", huber_rgb);
  v("t_dof", t_dof);
  v("t_sigma_rgb_init", t_sigma_rgb_init);
  v("t_sigma_rgb_min", t_sigma_rgb_min);
  v("min_gradient", min_gradient);
  v("photometric_occlusion_check", photometric_occlusion_check);
  v("occlusion_max_depth_m", occlusion_max_depth_m);
  v("finest_level_photometric_step", finest_level_photometric_step);
}

void PhotometricOptions::validate() const {
  require_option(finite_positive(huber_rgb), "huber_rgb must be finite and > 0");
  require_option(finite_positive(t_dof), "t_dof must be finite and > 0");
  require_option(finite_positive(t_sigma_rgb_init), "t_sigma_rgb_init must be finite and > 0");
  require_option(finite_positive(t_sigma_rgb_min), "t_sigma_rgb_min must be finite and > 0");
  require_option(std::isfinite(min_gradient) && min_gradient >= 0.0f, "min_gradient must be finite and >= 0");
  require_option(finite_positive(occlusion_max_depth_m), "occlusion_max_depth_m must be finite and > 0");
  require_option(finest_level_photometric_step >= 1 && finest_level_photometric_step <= 16,
                 "finest_level_photometric_step must be in 1..16");
}

hf_photometric_params PhotometricOptions::kernel_params(int level, float weight, float t_sigma) const {
  hf_photometric_params p{};
  p.weight = weight;
  p.robust = robust_params(robust_rgb, huber_rgb, t_sigma, t_dof);
  p.min_gradient_sq = min_gradient * min_gradient;
  p.occlusion_check = photometric_occlusion_check ? 1 : 0;
  p.occlusion_max_depth_m = occlusion_max_depth_m;
  p.step = level == 0 ? finest_level_photometric_step : 1;
  return p;
}

double PhotometricOptions::rows_possible(const FramePyramidLevel& current) const {
  return double(count_valid_pixels(current.vertices, finest_level_photometric_step));
}

const DenseKernel& photometric_kernel() { return kKernel; }

RegistrationMethod photometric_registration_method() { return {"photometric", defaults, make}; }

}  // namespace hf
