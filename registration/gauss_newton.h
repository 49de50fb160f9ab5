// The one Gauss-Newton driver every dense registration method runs on (report section 3: the methods share
// correspondences, coordinate system and solver).
//
// It owns: the coarse-to-fine loop over the pyramid (iterations per level from GaussNewtonOptions), the
// convergence test, the SE3 update T_ref_cur <- exp(xi) T_ref_cur by the exact exponential map (eq. 26), the
// degeneracy-aware 6x6 solve in double and the outcome checks. It never names a method: the method
// (registration/dense_method.h) supplies its kernel, its parameters per level (rejection gates, robust weights)
// and any per-iteration scale estimate; the backend sums the rows.
//
// The outcome rules are public, so a method that is not a per-pixel least-squares problem (NDT, sparse features)
// implements Registration directly and still reports the same statuses by the same rules: balanced_units() and
// solve_balanced_step() (degeneracy), classify_outcome() and verify_large_motion().
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "registration/dense_method.h"
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

// Degeneracy is judged on H with rotations expressed as displacements at the RMS distance L of the current points
// (omega * L, metres), so the eigenvalue ratio compares like with like and does not depend on how far the scene
// is: S = diag(1/L x3, 1 x3) for the valid vertices of `vertices` (L >= 1 mm).
Vector6d balanced_units(const VertexMap& vertices);
// The step of solve_gauss_newton_step for H' = S H S, g' = S g, mapped back (xi = S xi'); eigenvalues, condition
// and weakest direction in the balanced units.
GaussNewtonStep solve_balanced_step(const NormalEquations& ne, const Vector6d& unit_scale,
                                    double degeneracy_threshold);

// Fills result's information, eigenvalues, condition, inliers, cost and inlier ratio from the finest level's
// normal equations `last` and its balanced step, then its status, T_ref_cur and message by the shared rules: failed
// when the estimate moved beyond max_translation_m / max_rotation_deg from T_initial or its last step exceeds
// max_final_step_* (T_ref_cur = T_initial, information kept), else degenerate (degenerate_dims > 0), poor
// (inlier ratio below poor_inlier_ratio) or good, with T_ref_cur = T. rows_possible: the rows the finest level
// could have given. Returns false (result failed, T_initial) for a non-finite cost.
bool classify_outcome(const GaussNewtonOptions& options, const NormalEquations& last, const GaussNewtonStep& step,
                      double rows_possible, const SE3& T_initial, const SE3& T, const Vector6d& last_step,
                      RegistrationResult& result);

// Projective association can settle in a false minimum after a large motion; such minima are rarely symmetric.
// When `result` (usable) moved more than verify_motion_m / _deg from T_initial, `align_reverse` aligns the
// reference onto the current frame from T_initial^-1; unless that result is usable and its loop with `result` is
// within verify_agreement_m / _deg of the identity, `result` becomes failed with T_ref_cur = T_initial.
using ReverseAlignment = std::function<RegistrationResult(const SE3& T_cur_ref_initial)>;
void verify_large_motion(const GaussNewtonOptions& options, const SE3& T_initial, const ReverseAlignment& align_reverse,
                         RegistrationResult& result);

class GaussNewtonRegistration : public Registration {
 public:
  // Throws hf::Error for invalid options, a null method or a null backend.
  GaussNewtonRegistration(std::string name, std::unique_ptr<DenseMethod> method, const RegistrationOptions& options,
                          std::unique_ptr<ReductionBackend> backend);

  RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                           const SE3& T_ref_cur_initial) override;
  std::string name() const override { return name_; }
  const RegistrationOptions& options() const override { return options_; }
  bool aligns_to_volume() const override { return method_->aligns_to_volume(); }
  bool reads_colour() const override;
  void set_volume(const fusion::VoxelBlockGrid* grid, const SE3& T_world_ref) override {
    method_->set_volume(grid, T_world_ref);
  }
  ReductionBackend& backend() { return *backend_; }
  const DenseMethod& method() const { return *method_; }
  // The problem the driver reduces in the first iteration of pyramid `level` for the pair at T_ref_cur (for tests
  // and benchmarks: the same maps, kernel and parameters). It points into the pyramids and into this object's
  // method, so it is valid while both live and until the next align() or level_problem(). hf::Error for a level
  // either pyramid lacks.
  ResidualProblem level_problem(const FramePyramid& current, const FramePyramid& reference, int level,
                                const SE3& T_ref_cur);

 private:
  RegistrationResult align_impl(const FramePyramid& current, const FramePyramid& reference,
                                const SE3& T_ref_cur_initial);

  std::string name_;
  std::unique_ptr<DenseMethod> method_;
  RegistrationOptions options_;
  std::unique_ptr<ReductionBackend> backend_;
  std::uint64_t version_ = 0;
  VertexMap selected_vertices_;  // the current level's vertices under GaussNewtonOptions::row_selection
};

}  // namespace hf
