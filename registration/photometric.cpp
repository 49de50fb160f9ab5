#include "registration/photometric.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "core/error.h"
#include "registration/cpu_backend_avx2.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

constexpr unsigned kPhotometricInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_CUR_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_VERTICES) | HF_REG_IN_BIT(HF_REG_IN_REF_INTENSITY) |
                             HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_X) | HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_Y);
const DenseKernel kPhotometricKernel = make_dense_kernel<hf_photometric_params, hf_photometric_pixel>(
    "photometric", kPhotometricInputs, 1, &detail::photometric_rows_avx2);

class PhotometricMethod final : public DenseMethod {
 public:
  explicit PhotometricMethod(const PhotometricOptions& options) : options_(options) {}
  const DenseKernel& kernel() const override { return kPhotometricKernel; }
  void begin_level(int level, const FramePyramidLevel& current, const FramePyramidLevel& reference,
                   ResidualProblem& problem) override {
    params_ = options_.kernel_params(level, 1.0f, options_.t_sigma_rgb_init);
    if (options_.brightness_gain) {
      params_.gain =
          estimate_brightness_gain(current, reference, problem.T_ref_cur, options_.brightness_gain_max_ratio);
    }
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

RegistrationOptions photometric_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {20, 10, 10};
  return RegistrationOptions(driver, std::make_unique<PhotometricOptions>());
}

std::unique_ptr<Registration> make_photometric(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
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
  v("brightness_gain", brightness_gain);
  v("brightness_gain_max_ratio", brightness_gain_max_ratio);
}

float estimate_brightness_gain(const FramePyramidLevel& current, const FramePyramidLevel& reference,
                               const hf_transform12& T_ref_cur, float max_ratio, int step) {
  if (!current.has_intensity() || !reference.has_intensity() || current.width() != reference.width() ||
      current.height() != reference.height())
    return 1.0f;
  const hf_intrinsics K = current.camera.kernel_intrinsics();
  const int w = current.width(), h = current.height();
  step = std::max(1, step);
  std::vector<float> ic, ir;
  for (int y = 0; y < h; y += step) {
    for (int x = 0; x < w; x += step) {
      const size_t idx = size_t(y) * size_t(w) + size_t(x);
      const hf_float4 vc = current.vertices.data()[idx];
      if (!hf_is_valid4(vc)) continue;
      const hf_float4 v = hf_reg_transform_point(T_ref_cur, vc);
      if (!(v.z > 0.0f)) continue;
      float px, py, i_ref;
      hf_project(K, v, &px, &py);
      if (!hf_sample_bilinear(reference.intensity.data(), w, h, px, py, 0, &i_ref)) continue;
      const float i_cur = current.intensity.data()[idx];
      if (!std::isfinite(i_ref) || !std::isfinite(i_cur)) continue;
      ic.push_back(i_cur);
      ir.push_back(i_ref);
    }
  }
  if (ic.size() < 100) return 1.0f;
  auto median_abs_residual = [&](float gain, const std::vector<unsigned char>* use) {
    std::vector<float> r;
    r.reserve(ic.size());
    for (size_t i = 0; i < ic.size(); ++i)
      if (!use || (*use)[i]) r.push_back(std::fabs(ir[i] - gain * ic[i]));
    if (r.empty()) return 0.0f;
    std::nth_element(r.begin(), r.begin() + long(r.size() / 2), r.end());
    return r[r.size() / 2];
  };
  // The ratio of the means, then again without the pairs beyond 3 robust standard deviations of the residual
  // (occlusions, specularities, misaligned edges). A ratio of means, not a regression of I_ref on I_cur: a
  // misaligned pair lowers the correlation, which would shrink a regression's gain towards 0.
  std::vector<unsigned char> use(ic.size(), 1);
  double gain = 1.0;
  for (int round = 0; round < 2; ++round) {
    double sc = 0.0, sr = 0.0;
    for (size_t i = 0; i < ic.size(); ++i) {
      if (!use[i]) continue;
      sc += ic[i];
      sr += ir[i];
    }
    if (!(sc > 1e-6 * double(ic.size()))) return 1.0f;
    gain = std::clamp(sr / sc, 0.5, 2.0);
    if (round == 1) break;
    const float limit = 3.0f * 1.4826f * std::max(median_abs_residual(float(gain), nullptr), 1e-4f);
    for (size_t i = 0; i < ic.size(); ++i) use[i] = std::fabs(ir[i] - float(gain) * ic[i]) <= limit;
  }
  // Only where the gain explains the residual: its median under the gain at most max_ratio of the one under
  // constancy (the same pairs). A frame whose content changed gives a gain too, but one that explains little.
  const float constant = median_abs_residual(1.0f, &use), scaled = median_abs_residual(float(gain), &use);
  return scaled <= max_ratio * constant ? float(gain) : 1.0f;
}

void PhotometricOptions::validate() const {
  require_option(finite_positive(huber_rgb), "huber_rgb must be finite and > 0");
  require_option(finite_positive(t_dof), "t_dof must be finite and > 0");
  require_option(finite_positive(t_sigma_rgb_init), "t_sigma_rgb_init must be finite and > 0");
  require_option(finite_positive(t_sigma_rgb_min), "t_sigma_rgb_min must be finite and > 0");
  require_option(std::isfinite(min_gradient) && min_gradient >= 0.0f, "min_gradient must be finite and >= 0");
  require_option(finite_positive(occlusion_max_depth_m), "occlusion_max_depth_m must be finite and > 0");
  require_option(std::isfinite(brightness_gain_max_ratio) && brightness_gain_max_ratio >= 0.0f &&
                     brightness_gain_max_ratio <= 1.0f,
                 "brightness_gain_max_ratio must be in [0, 1]");
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
  p.gain = 1.0f;
  return p;
}

double PhotometricOptions::rows_possible(const FramePyramidLevel& current) const {
  return double(count_valid_pixels(current.vertices, finest_level_photometric_step));
}

const DenseKernel& photometric_kernel() { return kPhotometricKernel; }

RegistrationMethod photometric_registration_method() { return {"photometric", photometric_defaults, make_photometric}; }

}  // namespace hf
