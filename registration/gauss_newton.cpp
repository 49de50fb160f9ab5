#include "registration/gauss_newton.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <exception>
#include <numbers>

#include "core/error.h"
#include "registration/pixel_selection.h"
#include "registration/so3_prealign.h"

namespace hf {
namespace {

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

constexpr unsigned kIntensityInputs = HF_REG_IN_BIT(HF_REG_IN_CUR_INTENSITY) | HF_REG_IN_BIT(HF_REG_IN_REF_INTENSITY) |
                                      HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_X) | HF_REG_IN_BIT(HF_REG_IN_REF_GRAD_Y);

// The pyramid's maps in the slots the kernel reads (the others stay null, so a backend uploads nothing for them).
void set_pyramid_maps(const DenseKernel& kernel, const FramePyramidLevel& c, const FramePyramidLevel& r,
                      ResidualProblem& problem) {
  auto want = [&](int slot) { return (kernel.inputs & HF_REG_IN_BIT(slot)) != 0; };
  if (want(HF_REG_IN_CUR_VERTICES)) problem.set_map(HF_REG_IN_CUR_VERTICES, c.vertices.data());
  if (want(HF_REG_IN_CUR_NORMALS)) problem.set_map(HF_REG_IN_CUR_NORMALS, c.normals.data());
  if (want(HF_REG_IN_CUR_INTENSITY)) problem.set_map(HF_REG_IN_CUR_INTENSITY, c.intensity.data());
  if (want(HF_REG_IN_REF_VERTICES)) problem.set_map(HF_REG_IN_REF_VERTICES, r.vertices.data());
  if (want(HF_REG_IN_REF_NORMALS)) problem.set_map(HF_REG_IN_REF_NORMALS, r.normals.data());
  if (want(HF_REG_IN_REF_INTENSITY)) problem.set_map(HF_REG_IN_REF_INTENSITY, r.intensity.data());
  if (want(HF_REG_IN_REF_GRAD_X)) problem.set_map(HF_REG_IN_REF_GRAD_X, r.grad_x.data());
  if (want(HF_REG_IN_REF_GRAD_Y)) problem.set_map(HF_REG_IN_REF_GRAD_Y, r.grad_y.data());
}

}  // namespace

hf_reg_robust robust_params(RobustKernel kernel, float huber_k, float t_sigma, float t_dof) {
  hf_reg_robust r{HF_ROBUST_NONE, huber_k, t_dof};
  if (kernel == RobustKernel::huber) r.type = HF_ROBUST_HUBER;
  if (kernel == RobustKernel::student_t) {
    r.type = HF_ROBUST_STUDENT_T;
    r.scale = t_sigma;
  }
  return r;
}

long count_valid_pixels(const VertexMap& vertices, int step) {
  long n = 0;
  for (int y = 0; y < vertices.height(); y += step) {
    for (int x = 0; x < vertices.width(); x += step) n += vertices(x, y).w != 0.0f ? 1 : 0;
  }
  return n;
}

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

Vector6d balanced_units(const VertexMap& vertices) {
  double sum_sq = 0.0;
  long valid = 0;
  for (const hf_float4& v : vertices.pixels()) {
    if (v.w != 0.0f) {
      sum_sq += double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z;
      ++valid;
    }
  }
  const double L = std::max(1e-3, std::sqrt(sum_sq / double(std::max(1L, valid))));
  Vector6d unit_scale;
  unit_scale << 1.0 / L, 1.0 / L, 1.0 / L, 1.0, 1.0, 1.0;
  return unit_scale;
}

GaussNewtonStep solve_balanced_step(const NormalEquations& ne, const Vector6d& unit_scale,
                                    double degeneracy_threshold) {
  const Matrix6d Hs = unit_scale.asDiagonal() * ne.JtJ * unit_scale.asDiagonal();
  GaussNewtonStep step = solve_gauss_newton_step(Hs, unit_scale.cwiseProduct(ne.Jtr), degeneracy_threshold);
  step.xi = unit_scale.cwiseProduct(step.xi);
  return step;
}

bool classify_outcome(const GaussNewtonOptions& options, const NormalEquations& last, const GaussNewtonStep& step,
                      double rows_possible, const SE3& T_initial, const SE3& T, const Vector6d& last_step,
                      RegistrationResult& result) {
  result.information = last.JtJ;
  result.eigenvalues = step.eigenvalues;
  result.condition_number = std::isfinite(step.condition_number) ? step.condition_number : 0.0;
  result.degenerate_dims = step.degenerate_dims;
  result.weakest_direction = step.weakest_direction.allFinite() ? step.weakest_direction : Vector6d::Zero();
  result.inliers = last.count;
  result.final_cost = last.cost / double(std::max(1L, last.count));
  result.inlier_ratio = std::clamp(double(last.count) / std::max(1.0, rows_possible), 0.0, 1.0);
  result.T_ref_cur = T_initial;
  if (!std::isfinite(result.final_cost)) {
    result.final_cost = 0.0;
    result.status = RegistrationStatus::failed;
    result.message = "non-finite cost";
    return false;
  }
  const SE3 motion = T_initial.inverse() * T;
  const double angle_deg = motion.angle_rad() * 180.0 / std::numbers::pi;
  if (motion.translation().norm() > options.max_translation_m || angle_deg > options.max_rotation_deg) {
    // Keep the information for diagnostics but never hand out a wild pose.
    result.status = RegistrationStatus::failed;
    result.message = "diverged: the estimate moved " + std::to_string(motion.translation().norm()) + " m and " +
                     std::to_string(angle_deg) + " deg from the initial guess";
    return true;
  }
  if (last_step.head<3>().norm() > options.max_final_step_rotation_rad ||
      last_step.tail<3>().norm() > options.max_final_step_translation_m) {
    // Still moving after the last finest-level iteration: a slow slide along a valley, not a converged pose.
    result.status = RegistrationStatus::failed;
    result.message = "did not converge: the last step was " + std::to_string(last_step.tail<3>().norm()) +
                     " m and " + std::to_string(last_step.head<3>().norm()) + " rad";
    return true;
  }
  result.T_ref_cur = T;
  if (result.degenerate_dims > 0) {
    result.status = RegistrationStatus::degenerate;
    result.message = std::to_string(result.degenerate_dims) + " unconstrained direction(s) kept the initial guess";
  } else if (result.inlier_ratio < options.poor_inlier_ratio) {
    result.status = RegistrationStatus::poor;
    result.message = "inlier ratio " + std::to_string(result.inlier_ratio);
  } else {
    result.status = RegistrationStatus::good;
  }
  return true;
}

// Projective data association only sees correspondences within the method's gate around the current estimate, so
// a large motion can settle in a false minimum that looks as good as the true one (the `fast` preset: icp lands
// 0.41 m off with 78% inliers and a lower cost than a correct noisy room pair). Such minima are rarely symmetric:
// the reverse problem (reference onto current, from the inverse initial guess) falls elsewhere. Small motions
// (every TUM fr1 pair) skip the check.
void verify_large_motion(const GaussNewtonOptions& options, const SE3& T_initial, const ReverseAlignment& align_reverse,
                         RegistrationResult& result) {
  const SE3 motion = T_initial.inverse() * result.T_ref_cur;
  const double motion_deg = motion.angle_rad() * 180.0 / std::numbers::pi;
  if (motion.translation().norm() <= options.verify_motion_m && motion_deg <= options.verify_motion_deg) return;
  const RegistrationResult reverse = align_reverse(T_initial.inverse());
  const SE3 loop = result.T_ref_cur * reverse.T_ref_cur;  // identity when both agree
  const double loop_m = loop.translation().norm(), loop_deg = loop.angle_rad() * 180.0 / std::numbers::pi;
  if (reverse.usable() && loop_m <= options.verify_agreement_m && loop_deg <= options.verify_agreement_deg) return;
  result.status = RegistrationStatus::failed;
  result.message = "large motion (" + std::to_string(motion.translation().norm()) + " m, " +
                   std::to_string(motion_deg) + " deg) not confirmed by the reverse alignment (" +
                   (reverse.usable() ? "it disagrees by " + std::to_string(loop_m) + " m and " +
                                           std::to_string(loop_deg) + " deg"
                                     : std::string("status ") + to_string(reverse.status)) +
                   ")";
  result.T_ref_cur = T_initial;
}

GaussNewtonRegistration::GaussNewtonRegistration(std::string name, std::unique_ptr<DenseMethod> method,
                                                 const RegistrationOptions& options,
                                                 std::unique_ptr<ReductionBackend> backend)
    : name_(std::move(name)), method_(std::move(method)), options_(options), backend_(std::move(backend)) {
  options_.validate();
  if (!backend_) throw Error("registration '" + name_ + "': no reduction backend");
  if (!method_) throw Error("registration '" + name_ + "': no method");
  const DenseKernel& k = method_->kernel();
  if (k.rows == nullptr || k.pixel == nullptr || k.max_rows < 1 || k.max_rows > HF_REG_MAX_ROWS) {
    throw Error("registration '" + name_ + "': its kernel needs a pixel function and 1.." +
                std::to_string(HF_REG_MAX_ROWS) + " rows per pixel");
  }
}

bool GaussNewtonRegistration::reads_colour() const { return (method_->kernel().inputs & kIntensityInputs) != 0; }

RegistrationResult GaussNewtonRegistration::align(const FramePyramid& current, const FramePyramid& reference,
                                                  const SE3& T_ref_cur_initial) {
  const GaussNewtonOptions& o = options_.driver;
  RegistrationResult fallback;
  fallback.T_ref_cur = T_ref_cur_initial.is_finite() ? T_ref_cur_initial : SE3();
  fallback.iterations_per_level.assign(o.iterations.size(), 0);
  if (!T_ref_cur_initial.is_finite()) {
    fallback.status = RegistrationStatus::failed;
    fallback.message = "the initial guess is not finite";
    return fallback;
  }
  try {
    RegistrationResult result = align_impl(current, reference, T_ref_cur_initial);
    if (result.usable() && method_->reads_reference()) {
      verify_large_motion(
          o, T_ref_cur_initial, [&](const SE3& T_reverse) { return align_impl(reference, current, T_reverse); },
          result);
    }
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

ResidualProblem GaussNewtonRegistration::level_problem(const FramePyramid& current, const FramePyramid& reference,
                                                      int level, const SE3& T_ref_cur) {
  const bool reads_reference = method_->reads_reference();
  if (level < 0 || level >= current.num_levels() || (reads_reference && level >= reference.num_levels())) {
    throw Error("registration '" + name_ + "': no pyramid level " + std::to_string(level));
  }
  const FramePyramidLevel& c = current.levels[size_t(level)];
  const FramePyramidLevel& r = reads_reference ? reference.levels[size_t(level)] : c;
  ResidualProblem problem;
  problem.kernel = &method_->kernel();
  problem.camera = c.camera.kernel_intrinsics();
  set_pyramid_maps(*problem.kernel, c, r, problem);
  problem.T_ref_cur = to_transform12(T_ref_cur);  // begin_level may read the estimate (photometric's brightness)
  method_->begin_level(level, c, r, problem);
  const PixelSelectionOptions& selection = options_.driver.row_selection;
  if (selection.enabled() && level < selection.levels &&
      (problem.kernel->inputs & HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES)) != 0) {
    // Rows only at the selected pixels: their vertices alone stay valid, which every kernel and backend honours.
    selected_vertices_ = c.vertices;
    apply_pixel_selection(select_pixels(c, selection), &selected_vertices_);
    problem.set_map(HF_REG_IN_CUR_VERTICES, selected_vertices_.data());
  }
  problem.params = method_->params();
  problem.pixel_step = method_->pixel_step();
  problem.inputs_version = ++version_;
  problem.T_ref_cur = to_transform12(T_ref_cur);
  return problem;
}

RegistrationResult GaussNewtonRegistration::align_impl(const FramePyramid& current, const FramePyramid& reference,
                                                       const SE3& T_initial) {
  const GaussNewtonOptions& o = options_.driver;
  const DenseKernel& kernel = method_->kernel();
  RegistrationResult result;
  result.T_ref_cur = T_initial;
  result.iterations_per_level.assign(o.iterations.size(), 0);
  const bool reads_reference = method_->reads_reference();
  const int levels = std::min({int(o.iterations.size()), current.num_levels(),
                               reads_reference ? reference.num_levels() : current.num_levels()});
  auto fail = [&](RegistrationStatus status, const std::string& message) {
    result.T_ref_cur = T_initial;
    result.status = status;
    result.message = message;
    return result;
  };
  if (levels < 1) return fail(RegistrationStatus::no_data, "empty pyramid");
  for (int l = 0; l < levels; ++l) {
    const FramePyramidLevel& c = current.levels[size_t(l)];
    const FramePyramidLevel& r = reads_reference ? reference.levels[size_t(l)] : c;
    if (!level_consistent(c) || !level_consistent(r) || !same_camera(c.camera, r.camera)) {
      return fail(RegistrationStatus::failed,
                  "level " + std::to_string(l) + ": the current and reference maps differ in camera or size");
    }
    if ((kernel.inputs & kIntensityInputs) != 0 && (!c.has_intensity() || !r.has_intensity())) {
      return fail(RegistrationStatus::no_data, name_ + " needs intensity in both frames");
    }
  }
  const long valid_cur = count_valid_pixels(current.levels[0].vertices);
  const long valid_ref = reads_reference ? count_valid_pixels(reference.levels[0].vertices) : valid_cur;
  if (valid_cur < o.min_inliers || valid_ref < o.min_inliers) {
    return fail(RegistrationStatus::no_data, "too few valid pixels (current " + std::to_string(valid_cur) +
                                                 ", reference " + std::to_string(valid_ref) + ")");
  }
  const Vector6d unit_scale = balanced_units(current.levels[0].vertices);

  SE3 T = T_initial;
  if (!o.so3_iterations.empty() && (kernel.inputs & kIntensityInputs) != 0) {
    // Rotation first (registration/so3_prealign.h) on the levels this solve uses; the translation keeps its guess.
    const So3PrealignResult so3 = so3_prealign(current, reference, T_initial.rotation(), o.so3_iterations, levels);
    if (so3.accepted) T = SE3(so3.R_ref_cur, T_initial.translation());
  }
  NormalEquations last;
  std::vector<NormalEquations> last_terms;
  Vector6d last_step = Vector6d::Zero();
  bool have_last = false;
  const std::vector<std::string> term_names = method_->term_names();
  for (int l = levels - 1; l >= 0; --l) {
    ResidualProblem problem = level_problem(current, reference, l, T);
    std::vector<ResidualProblem> term_problems;
    for (int t = 0; t < int(term_names.size()); ++t) term_problems.push_back(method_->term_problem(t, problem));
    for (int it = 0; it < o.iterations[size_t(l)]; ++it) {
      problem.T_ref_cur = to_transform12(T);
      std::vector<NormalEquations> terms;
      for (ResidualProblem& tp : term_problems) {
        tp.T_ref_cur = problem.T_ref_cur;
        terms.push_back(backend_->reduce(tp));
      }
      if (it == 0 && !terms.empty()) {
        method_->probe_terms(terms, unit_scale, [&](int t, const Vector6d& xi) {
          ResidualProblem moved = term_problems[size_t(t)];
          moved.T_ref_cur = to_transform12(SE3::exp(xi) * T);
          return backend_->reduce(moved);
        });
      }
      const NormalEquations ne = terms.empty() ? backend_->reduce(problem) : method_->combine_terms(terms, unit_scale);
      if (l == 0) {
        last = ne;
        last_terms = terms;
        have_last = true;
      }
      if (ne.count < 6) break;  // nothing to solve on this level; the finest level decides the outcome
      const GaussNewtonStep step = solve_balanced_step(ne, unit_scale, o.degeneracy_threshold);
      if (!step.finite) return fail(RegistrationStatus::failed, "non-finite normal equations");
      method_->end_iteration(ne);
      T = SE3::exp(step.xi) * T;
      if (l == 0) last_step = step.xi;
      ++result.iterations_per_level[size_t(l)];
      if (!T.is_finite()) return fail(RegistrationStatus::failed, "the estimate became non-finite");
      if (step.xi.head<3>().norm() < o.min_step_rotation_rad && step.xi.tail<3>().norm() < o.min_step_translation_m) {
        break;
      }
    }
  }

  if (!have_last || last.count < o.min_inliers) {
    return fail(RegistrationStatus::failed, "too few correspondences at the finest level (" +
                                                std::to_string(have_last ? last.count : 0) + ")");
  }
  const GaussNewtonStep final_step = solve_balanced_step(last, unit_scale, o.degeneracy_threshold);
  if (!final_step.finite) return fail(RegistrationStatus::failed, "non-finite normal equations");
  // With a row selection on the finest level, the rows possible are those of its selected pixels (the level's
  // problem, the last one made, left them in selected_vertices_).
  double rows_possible = 0.0;
  if (o.row_selection.enabled() && !selected_vertices_.empty() &&
      selected_vertices_.size() == current.levels[0].vertices.size()) {
    FramePyramidLevel selected;
    selected.camera = current.levels[0].camera;
    selected.vertices = std::move(selected_vertices_);
    rows_possible = method_->rows_possible(selected);
    selected_vertices_ = std::move(selected.vertices);
  } else {
    rows_possible = method_->rows_possible(current.levels[0]);
  }
  classify_outcome(o, last, final_step, rows_possible, T_initial, T, last_step, result);
  for (size_t t = 0; t < last_terms.size(); ++t) {
    const NormalEquations& ne = last_terms[t];
    const GaussNewtonStep own = solve_balanced_step(ne, unit_scale, o.degeneracy_threshold);
    result.terms.push_back({term_names[t], ne.JtJ, ne.count, ne.Jtr, ne.cost,
                            own.finite ? own.xi : Vector6d::Zero()});
  }
  return result;
}

}  // namespace hf
