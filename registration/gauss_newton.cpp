#include "registration/gauss_newton.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <exception>
#include <numbers>

#include "core/error.h"

namespace hf {
namespace {

int to_kernel(RobustKernel k) {
  switch (k) {
    case RobustKernel::huber: return HF_ROBUST_HUBER;
    case RobustKernel::student_t: return HF_ROBUST_STUDENT_T;
    case RobustKernel::none: break;
  }
  return HF_ROBUST_NONE;
}

// Valid vertices on the pixel grid x, y = 0, step, 2 step, ...
long count_valid(const VertexMap& vertices, int step = 1) {
  long n = 0;
  for (int y = 0; y < vertices.height(); y += step) {
    for (int x = 0; x < vertices.width(); x += step) n += vertices(x, y).w != 0.0f ? 1 : 0;
  }
  return n;
}

bool same_camera(const PinholeCamera& a, const PinholeCamera& b) {
  return a.width == b.width && a.height == b.height && std::abs(a.fx - b.fx) < 1e-9 && std::abs(a.fy - b.fy) < 1e-9 &&
         std::abs(a.cx - b.cx) < 1e-9 && std::abs(a.cy - b.cy) < 1e-9;
}

bool level_consistent(const FramePyramidLevel& level) {
  const size_t n = size_t(level.camera.width) * size_t(level.camera.height);
  return level.camera.width > 0 && level.camera.height > 0 && level.vertices.size() == n &&
         level.normals.size() == n &&
         (level.intensity.empty() ||
          (level.intensity.size() == n && level.grad_x.size() == n && level.grad_y.size() == n));
}

}  // namespace

GaussNewtonStep solve_gauss_newton_step(const Matrix6d& H, const Vector6d& g, double degeneracy_threshold) {
  GaussNewtonStep step;
  if (!H.allFinite() || !g.allFinite()) return step;
  step.finite = true;
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eig(H);
  if (eig.info() != Eigen::Success) {
    step.finite = false;
    return step;
  }
  step.eigenvalues = eig.eigenvalues();
  step.weakest_direction = eig.eigenvectors().col(0);
  const double lmax = step.eigenvalues(5), lmin = step.eigenvalues(0);
  step.condition_number = lmin > 0.0 ? lmax / lmin : 0.0;
  step.degenerate_dims = 0;
  for (int i = 0; i < 6; ++i) {
    const double li = step.eigenvalues(i);
    if (!(lmax > 0.0) || li <= degeneracy_threshold * lmax) {
      ++step.degenerate_dims;
      continue;
    }
    const Vector6d vi = eig.eigenvectors().col(i);
    step.xi -= (vi.dot(g) / li) * vi;
  }
  if (!step.xi.allFinite()) {
    step.xi.setZero();
    step.finite = false;
  }
  return step;
}

const char* to_string(RegistrationStatus status) {
  switch (status) {
    case RegistrationStatus::good: return "good";
    case RegistrationStatus::poor: return "poor";
    case RegistrationStatus::degenerate: return "degenerate";
    case RegistrationStatus::failed: return "failed";
    case RegistrationStatus::no_data: return "no-data";
  }
  return "unknown";
}

GaussNewtonRegistration::GaussNewtonRegistration(std::string name, int method, const RegistrationOptions& options,
                                                 std::unique_ptr<ReductionBackend> backend)
    : name_(std::move(name)), method_(method), options_(options), backend_(std::move(backend)) {
  options_.validate();
  if (!backend_) throw Error("registration '" + name_ + "': no reduction backend");
  if (method_ != HF_REG_ICP && method_ != HF_REG_PHOTOMETRIC && method_ != HF_REG_COMBINED) {
    throw Error("registration '" + name_ + "': unknown method id " + std::to_string(method_));
  }
}

hf_reg_params GaussNewtonRegistration::level_params(int level) const {
  hf_reg_params p{};
  p.method = method_;
  // The same gate on every level (KinectFusion): a wider coarse gate pulls the fast preset into wrong minima.
  p.max_dist_m = options_.max_dist_m;
  p.min_normal_cos = float(std::cos(double(options_.max_normal_angle_deg) * std::numbers::pi / 180.0));
  p.icp_weight = 1.0f;
  p.rgb_weight = method_ == HF_REG_COMBINED ? options_.rgb_weight : 1.0f;
  p.robust_icp = to_kernel(options_.robust_icp);
  p.scale_icp = options_.robust_icp == RobustKernel::student_t ? options_.t_sigma_icp_m : options_.huber_icp_m;
  p.robust_rgb = to_kernel(options_.robust_rgb);
  p.scale_rgb = options_.robust_rgb == RobustKernel::student_t ? options_.t_sigma_rgb_init : options_.huber_rgb;
  p.t_dof = options_.t_dof;
  p.min_gradient_sq = options_.min_gradient * options_.min_gradient;
  p.occlusion_check = options_.photometric_occlusion_check ? 1 : 0;
  p.photometric_step = level == 0 ? options_.finest_level_photometric_step : 1;
  return p;
}

RegistrationResult GaussNewtonRegistration::align(const FramePyramid& current, const FramePyramid& reference,
                                                  const SE3& T_ref_cur_initial) {
  RegistrationResult fallback;
  fallback.T_ref_cur = T_ref_cur_initial.is_finite() ? T_ref_cur_initial : SE3();
  fallback.iterations_per_level.assign(options_.iterations.size(), 0);
  if (!T_ref_cur_initial.is_finite()) {
    fallback.status = RegistrationStatus::failed;
    fallback.message = "the initial guess is not finite";
    return fallback;
  }
  try {
    RegistrationResult result = align_impl(current, reference, T_ref_cur_initial);
    if (result.usable()) verify_large_motion(current, reference, T_ref_cur_initial, result);
    return result;
  } catch (const std::exception& e) {
    fallback.status = RegistrationStatus::failed;
    fallback.message = std::string("registration error: ") + e.what();
  } catch (...) {
    fallback.status = RegistrationStatus::failed;
    fallback.message = "registration error";
  }
  return fallback;
}

// Projective data association only sees correspondences within max_dist_m of the current estimate, so a large
// motion can settle in a false minimum that looks as good as the true one (the `fast` preset: icp lands 0.41 m
// off with 78% inliers and a lower cost than a correct noisy room pair). Such minima are rarely symmetric: the
// reverse problem (reference onto current, from the inverse initial guess) falls elsewhere. So a result that
// moved more than verify_motion_m / verify_motion_deg from the guess is only kept when the reverse alignment
// agrees with its inverse to within verify_agreement_m / _deg; small motions (every TUM fr1 pair) skip the check.
void GaussNewtonRegistration::verify_large_motion(const FramePyramid& current, const FramePyramid& reference,
                                                  const SE3& T_initial, RegistrationResult& result) {
  const SE3 motion = T_initial.inverse() * result.T_ref_cur;
  const double motion_deg = motion.angle_rad() * 180.0 / std::numbers::pi;
  if (motion.translation().norm() <= options_.verify_motion_m && motion_deg <= options_.verify_motion_deg) return;
  const RegistrationResult reverse = align_impl(reference, current, T_initial.inverse());
  const SE3 loop = result.T_ref_cur * reverse.T_ref_cur;  // identity when both agree
  const double loop_m = loop.translation().norm(), loop_deg = loop.angle_rad() * 180.0 / std::numbers::pi;
  if (reverse.usable() && loop_m <= options_.verify_agreement_m && loop_deg <= options_.verify_agreement_deg) return;
  result.status = RegistrationStatus::failed;
  result.message = "large motion (" + std::to_string(motion.translation().norm()) + " m, " +
                   std::to_string(motion_deg) + " deg) not confirmed by the reverse alignment (" +
                   (reverse.usable() ? "it disagrees by " + std::to_string(loop_m) + " m and " +
                                           std::to_string(loop_deg) + " deg"
                                     : std::string("status ") + to_string(reverse.status)) +
                   ")";
  result.T_ref_cur = T_initial;
}

RegistrationResult GaussNewtonRegistration::align_impl(const FramePyramid& current, const FramePyramid& reference,
                                                       const SE3& T_initial) {
  RegistrationResult result;
  result.T_ref_cur = T_initial;
  result.iterations_per_level.assign(options_.iterations.size(), 0);
  const bool photometric = method_ != HF_REG_ICP;
  const int levels =
      std::min({int(options_.iterations.size()), current.num_levels(), reference.num_levels()});
  auto fail = [&](RegistrationStatus status, const std::string& message) {
    result.T_ref_cur = T_initial;
    result.status = status;
    result.message = message;
    return result;
  };
  if (levels < 1) return fail(RegistrationStatus::no_data, "empty pyramid");
  for (int l = 0; l < levels; ++l) {
    const FramePyramidLevel& c = current.levels[size_t(l)];
    const FramePyramidLevel& r = reference.levels[size_t(l)];
    if (!level_consistent(c) || !level_consistent(r) || !same_camera(c.camera, r.camera)) {
      return fail(RegistrationStatus::failed,
                  "level " + std::to_string(l) + ": the current and reference maps differ in camera or size");
    }
    if (photometric && (!c.has_intensity() || !r.has_intensity())) {
      return fail(RegistrationStatus::no_data, name_ + " needs intensity in both frames");
    }
  }
  const long valid_cur = count_valid(current.levels[0].vertices);
  const long valid_ref = count_valid(reference.levels[0].vertices);
  if (valid_cur < options_.min_inliers || valid_ref < options_.min_inliers) {
    return fail(RegistrationStatus::no_data, "too few valid pixels (current " + std::to_string(valid_cur) +
                                                 ", reference " + std::to_string(valid_ref) + ")");
  }

  // Degeneracy is judged on H with rotations expressed as displacements at the RMS distance L of the current
  // points (omega * L, metres), so the eigenvalue ratio compares like with like and does not depend on how far
  // the scene is.
  double sum_sq = 0.0;
  for (const hf_float4& v : current.levels[0].vertices.pixels()) {
    if (v.w != 0.0f) sum_sq += double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z;
  }
  const double L = std::max(1e-3, std::sqrt(sum_sq / double(valid_cur)));
  Vector6d unit_scale;
  unit_scale << 1.0 / L, 1.0 / L, 1.0 / L, 1.0, 1.0, 1.0;
  auto solve = [&](const NormalEquations& ne) {
    // H' = S H S, g' = S g with xi = S xi': the step is solved in the balanced units and mapped back.
    const Matrix6d Hs = unit_scale.asDiagonal() * ne.JtJ * unit_scale.asDiagonal();
    GaussNewtonStep step = solve_gauss_newton_step(Hs, unit_scale.cwiseProduct(ne.Jtr), options_.degeneracy_threshold);
    step.xi = unit_scale.cwiseProduct(step.xi);
    return step;
  };

  SE3 T = T_initial;
  NormalEquations last;
  Vector6d last_step = Vector6d::Zero();
  bool have_last = false;
  const bool estimate_sigma = method_ == HF_REG_PHOTOMETRIC && options_.robust_rgb == RobustKernel::student_t;
  for (int l = levels - 1; l >= 0; --l) {
    const FramePyramidLevel& c = current.levels[size_t(l)];
    const FramePyramidLevel& r = reference.levels[size_t(l)];
    ResidualProblem problem;
    problem.camera = c.camera.kernel_intrinsics();
    problem.cur_vertices = c.vertices.data();
    problem.cur_normals = c.normals.data();
    problem.ref_vertices = r.vertices.data();
    problem.ref_normals = r.normals.data();
    if (photometric) {
      problem.cur_intensity = c.intensity.data();
      problem.ref_intensity = r.intensity.data();
      problem.ref_grad_x = r.grad_x.data();
      problem.ref_grad_y = r.grad_y.data();
    }
    problem.params = level_params(l);
    problem.inputs_version = ++version_;
    float sigma_rgb = options_.t_sigma_rgb_init;
    for (int it = 0; it < options_.iterations[size_t(l)]; ++it) {
      problem.T_ref_cur = to_transform12(T);
      if (estimate_sigma) problem.params.scale_rgb = sigma_rgb;
      const NormalEquations ne = backend_->reduce(problem);
      if (l == 0) {
        last = ne;
        have_last = true;
      }
      if (ne.count < 6) break;  // nothing to solve on this level; the finest level decides the outcome
      const GaussNewtonStep step = solve(ne);
      if (!step.finite) return fail(RegistrationStatus::failed, "non-finite normal equations");
      if (estimate_sigma && ne.count > 0) {
        // DVO: sigma^2 = 1/n sum r^2 (nu + 1) / (nu + r^2 / sigma^2), i.e. cost / count under the current weights.
        sigma_rgb = std::max(options_.t_sigma_rgb_min, float(std::sqrt(ne.cost / double(ne.count))));
      }
      T = SE3::exp(step.xi) * T;
      if (l == 0) last_step = step.xi;
      ++result.iterations_per_level[size_t(l)];
      if (!T.is_finite()) return fail(RegistrationStatus::failed, "the estimate became non-finite");
      if (step.xi.head<3>().norm() < options_.min_step_rotation_rad &&
          step.xi.tail<3>().norm() < options_.min_step_translation_m) {
        break;
      }
    }
  }

  if (!have_last || last.count < options_.min_inliers) {
    return fail(RegistrationStatus::failed, "too few correspondences at the finest level (" +
                                                std::to_string(have_last ? last.count : 0) + ")");
  }
  const GaussNewtonStep final_step = solve(last);
  if (!final_step.finite) return fail(RegistrationStatus::failed, "non-finite normal equations");
  result.information = last.JtJ;
  result.eigenvalues = final_step.eigenvalues;
  result.condition_number = std::isfinite(final_step.condition_number) ? final_step.condition_number : 0.0;
  result.degenerate_dims = final_step.degenerate_dims;
  result.weakest_direction = final_step.weakest_direction.allFinite() ? final_step.weakest_direction : Vector6d::Zero();
  result.inliers = last.count;
  result.final_cost = last.cost / double(last.count);
  // Rows possible at the finest level: one per valid pixel for icp, one per valid pixel on the photometric grid
  // for photometric, both for combined.
  const long valid_grid = count_valid(current.levels[0].vertices, options_.finest_level_photometric_step);
  const double possible = method_ == HF_REG_ICP ? double(valid_cur)
                          : method_ == HF_REG_PHOTOMETRIC ? double(valid_grid)
                                                          : double(valid_cur + valid_grid);
  result.inlier_ratio = std::clamp(double(last.count) / std::max(1.0, possible), 0.0, 1.0);
  if (!std::isfinite(result.final_cost)) return fail(RegistrationStatus::failed, "non-finite cost");

  const SE3 motion = T_initial.inverse() * T;
  const double angle_deg = motion.angle_rad() * 180.0 / std::numbers::pi;
  if (motion.translation().norm() > options_.max_translation_m || angle_deg > options_.max_rotation_deg) {
    // Keep the information for diagnostics but never hand out a wild pose.
    result.T_ref_cur = T_initial;
    result.status = RegistrationStatus::failed;
    result.message = "diverged: the estimate moved " + std::to_string(motion.translation().norm()) + " m and " +
                     std::to_string(angle_deg) + " deg from the initial guess";
    return result;
  }
  if (last_step.head<3>().norm() > options_.max_final_step_rotation_rad ||
      last_step.tail<3>().norm() > options_.max_final_step_translation_m) {
    // Still moving after the last finest-level iteration: a slow slide along a valley, not a converged pose.
    result.T_ref_cur = T_initial;
    result.status = RegistrationStatus::failed;
    result.message = "did not converge: the last step was " + std::to_string(last_step.tail<3>().norm()) +
                     " m and " + std::to_string(last_step.head<3>().norm()) + " rad";
    return result;
  }
  result.T_ref_cur = T;
  if (result.degenerate_dims > 0) {
    result.status = RegistrationStatus::degenerate;
    result.message = std::to_string(result.degenerate_dims) + " unconstrained direction(s) kept the initial guess";
  } else if (result.inlier_ratio < options_.poor_inlier_ratio) {
    result.status = RegistrationStatus::poor;
    result.message = "inlier ratio " + std::to_string(result.inlier_ratio);
  } else {
    result.status = RegistrationStatus::good;
  }
  return result;
}

}  // namespace hf
