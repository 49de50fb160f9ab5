// The one Gauss-Newton driver every dense registration method runs on (report section 3: the methods share
// correspondences, coordinate system and solver).
//
// It owns: the coarse-to-fine loop over the pyramid (iterations per level from RegistrationOptions), the
// convergence test, the SE3 update T_ref_cur <- exp(xi) T_ref_cur by the exact exponential map (eq. 26), the
// correspondence rejection thresholds (distance, normal angle), the robust weights by IRLS (Huber; Student-t with
// DVO's scale re-estimation), the degeneracy-aware 6x6 solve in double and the outcome checks. A method only
// names its per-pixel residual (registration/kernels/residuals.h, HF_REG_*); the backend sums the rows.
#pragma once

#include <memory>
#include <string>

#include "registration/registration.h"

namespace hf {

// The step of one iteration: xi minimising |J xi + r|_W, i.e. H xi = -g, solved by eigen-decomposition of H in
// double. Eigen-directions with lambda_i <= threshold * lambda_max (or lambda_max <= 0) are degenerate: the step
// has no component along them (the estimate keeps the prior motion there, Zhang et al. 2016).
struct GaussNewtonStep {
  Vector6d xi = Vector6d::Zero();
  Vector6d eigenvalues = Vector6d::Zero();  // ascending
  int degenerate_dims = 6;
  double condition_number = 0.0;  // lambda_max / lambda_min, 0 when lambda_min <= 0
  Vector6d weakest_direction = Vector6d::Zero();  // unit eigenvector of the smallest eigenvalue
  bool finite = false;            // H and g were finite
};
GaussNewtonStep solve_gauss_newton_step(const Matrix6d& H, const Vector6d& g, double degeneracy_threshold);

class GaussNewtonRegistration : public Registration {
 public:
  // method: HF_REG_ICP, HF_REG_PHOTOMETRIC or HF_REG_COMBINED. Throws hf::Error for invalid options or a null
  // backend.
  GaussNewtonRegistration(std::string name, int method, const RegistrationOptions& options,
                          std::unique_ptr<ReductionBackend> backend);

  RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                           const SE3& T_ref_cur_initial) override;
  std::string name() const override { return name_; }
  const RegistrationOptions& options() const override { return options_; }
  ReductionBackend& backend() { return *backend_; }

 private:
  RegistrationResult align_impl(const FramePyramid& current, const FramePyramid& reference,
                                const SE3& T_ref_cur_initial);
  // Marks a usable result failed (T = the initial guess) when it moved far and the reverse alignment does not
  // confirm it (see gauss_newton.cpp).
  void verify_large_motion(const FramePyramid& current, const FramePyramid& reference, const SE3& T_initial,
                           RegistrationResult& result);
  hf_reg_params level_params(int level) const;

  std::string name_;
  int method_;
  RegistrationOptions options_;
  std::unique_ptr<ReductionBackend> backend_;
  std::uint64_t version_ = 0;
};

}  // namespace hf
