#include "registration/mrsmap.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "registration/gauss_newton.h"
#include "registration/ndt/ndt_newton.h"

namespace hf {

void MrsmapOptions::visit(OptionVisitor& v) {
  NdtOptions::visit(v);
  v("descriptor_max_distance", descriptor_max_distance);
  v("luminance_step", luminance_step);
  v("lm_iterations", lm_iterations);
}

void MrsmapOptions::validate() const {
  NdtOptions::validate();
  require_option(finite_positive(descriptor_max_distance), "descriptor_max_distance must be finite and > 0");
  require_option(luminance_step >= 0.0 && luminance_step < 1.0, "luminance_step must be in [0, 1)");
  require_option(lm_iterations >= 0 && lm_iterations <= 100, "lm_iterations must be in 0..100");
}

namespace {

Eigen::Vector3d towards_origin(const NdtCell& c) { return c.normal().dot(c.mean) > 0.0 ? -c.normal() : c.normal(); }

int bin3(double x, double lo, double hi) { return std::clamp(int((x - lo) / (hi - lo) * 3.0), 0, 2); }

}  // namespace

SurfelDescriptor surfel_descriptor(const NdtGrid& grid, const NdtCell& surfel, double luminance_step) {
  SurfelDescriptor h = SurfelDescriptor::Zero();
  std::vector<const NdtCell*> neighbours;
  grid.neighbourhood(surfel.mean, 27, &neighbours);
  const Eigen::Vector3d u = towards_origin(surfel);
  int counted = 0;
  for (const NdtCell* t : neighbours) {
    if (t == &surfel) continue;
    const Eigen::Vector3d d = t->mean - surfel.mean;
    Eigen::Vector3d v = u.cross(d);
    if (!(d.norm() > 0.0) || !(v.norm() > 1e-9 * d.norm())) continue;  // a neighbour along the normal: no frame
    v.normalize();
    const Eigen::Vector3d w = u.cross(v);
    const Eigen::Vector3d n_t = towards_origin(*t);
    h(bin3(v.dot(n_t), -1.0, 1.0)) += 1.0;
    h(3 + bin3(u.dot(d.normalized()), -1.0, 1.0)) += 1.0;
    h(6 + bin3(std::atan2(w.dot(n_t), u.dot(n_t)), -std::numbers::pi, std::numbers::pi)) += 1.0;
    const double dl = t->colour_mean - surfel.colour_mean;
    h(9 + (dl < -luminance_step ? 0 : dl > luminance_step ? 2 : 1)) += 1.0;
    ++counted;
  }
  if (counted > 0) h /= double(counted);
  return h;
}

namespace {

// One resolution of a surfel map: the cells with their luminance, and each cell's descriptor (by cells() index).
struct SurfelLevel {
  NdtGrid grid;
  std::vector<SurfelDescriptor> descriptors;
};

std::vector<SurfelLevel> surfel_map(const NdtSamples& s, const MrsmapOptions& o) {
  std::vector<SurfelLevel> map;
  const bool colour = s.has_intensity();
  for (const double cell_m : o.resolutions_m()) {
    SurfelLevel level{NdtGrid(cell_m, o.grid), {}};
    for (size_t i = 0; i < s.points.size(); ++i) level.grid.add(s.points[i], 1.0, colour ? s.intensity[i] : 0.0);
    level.grid.finish();
    for (const NdtCell& c : level.grid.cells()) {
      level.descriptors.push_back(surfel_descriptor(level.grid, c, o.luminance_step));
    }
    map.push_back(std::move(level));
  }
  return map;
}

// For each level (coarsest first), each current surfel moved by T against every reference surfel of the 7 cells
// around it (its cell and its face neighbours: ndt-d2d's association) whose descriptor is close enough.
std::vector<NdtLevel> surfel_levels(const std::vector<SurfelLevel>& cur, const std::vector<SurfelLevel>& ref,
                                    double max_descriptor_distance) {
  std::vector<NdtLevel> levels;
  for (size_t l = 0; l < cur.size() && l < ref.size(); ++l) {
    NdtLevel level;
    level.cell_m = ref[l].grid.cell_m();
    level.associate = [&c = cur[l], &r = ref[l], max_descriptor_distance](const SE3& T, std::vector<NdtTerm>* terms) {
      terms->clear();
      std::vector<const NdtCell*> candidates;
      const Eigen::Matrix3d R = T.rotation();
      const NdtCell* ref_cells = r.grid.cells().data();
      for (size_t i = 0; i < c.grid.cells().size(); ++i) {
        const NdtCell& s = c.grid.cells()[i];
        r.grid.neighbourhood(R * s.mean + T.translation(), 7, &candidates);
        for (const NdtCell* m : candidates) {
          if ((c.descriptors[i] - r.descriptors[size_t(m - ref_cells)]).norm() > max_descriptor_distance) continue;
          NdtTerm term;
          if (distribution_term(s, *m, R, r.grid.cell_m(), &term)) terms->push_back(term);
        }
      }
    };
    levels.push_back(std::move(level));
  }
  return levels;
}

// Sum of the pairs' squared Mahalanobis distances x'^T C^-1 x' at T, and (when H is given) the Gauss-Newton
// normal equations of the left perturbation and the constraining information (ndt_newton.h).
double mahalanobis_cost(const std::vector<NdtTerm>& terms, const SE3& T, Matrix6d* H = nullptr, Vector6d* g = nullptr,
                        Matrix6d* information = nullptr) {
  double cost = 0.0;
  const Eigen::Matrix3d R = T.rotation();
  for (const NdtTerm& term : terms) {
    const Eigen::Vector3d x = R * term.p + T.translation();
    const Eigen::Vector3d r = x - term.mean;
    const double q = r.dot(term.C_inv * r);
    if (!std::isfinite(q)) continue;
    cost += term.weight * q;
    if (H == nullptr) continue;
    Eigen::Matrix<double, 3, 6> J;
    J.leftCols<3>() = -skew(x);
    J.rightCols<3>().setIdentity();
    *H += term.weight * J.transpose() * term.C_inv * J;
    *g += term.weight * J.transpose() * term.C_inv * r;
    *information += J.transpose() * term.W_information * J;
  }
  return cost;
}

// Levenberg-Marquardt (Marquardt's diagonal damping, lambda / 10 on success, x 10 on failure) over the levels,
// coarsest first, re-associating each iteration; steps along the degenerate directions are removed as in Newton.
SE3 levenberg_marquardt(const std::vector<NdtLevel>& levels, int iterations, const SE3& T_start,
                        const NdtSolveOptions& so, const GaussNewtonOptions& driver) {
  SE3 T = T_start;
  std::vector<NdtTerm> terms;
  for (const NdtLevel& level : levels) {
    double lambda = 1e-4;
    for (int it = 0; it < iterations; ++it) {
      level.associate(T, &terms);
      if (terms.size() < 6) break;
      Matrix6d H = Matrix6d::Zero(), information = Matrix6d::Zero();
      Vector6d g = Vector6d::Zero();
      const double cost = mahalanobis_cost(terms, T, &H, &g, &information);
      if (!H.allFinite() || !g.allFinite()) return T_start;
      const Matrix6d tiny = 1e-12 * std::max(H.trace(), 1e-300) * Matrix6d::Identity();
      bool accepted = false;
      Vector6d xi = Vector6d::Zero();
      for (int attempt = 0; attempt < 10 && !accepted; ++attempt, lambda *= 10.0) {
        const Matrix6d A = H + lambda * Matrix6d(H.diagonal().asDiagonal()) + tiny;
        xi = project_out_degenerate(-A.ldlt().solve(g), information, so.unit_scale, driver.degeneracy_threshold);
        if (!xi.allFinite()) return T;
        accepted = mahalanobis_cost(terms, SE3::exp(xi) * T) < cost;
      }
      if (!accepted) break;
      lambda = std::max(lambda / 100.0, 1e-9);  // the loop multiplied once after the successful attempt
      T = SE3::exp(xi) * T;
      if (xi.head<3>().norm() < driver.min_step_rotation_rad && xi.tail<3>().norm() < driver.min_step_translation_m) {
        break;
      }
    }
  }
  return T.is_finite() ? T : T_start;
}

// Surfel pairs at the finest level below which the estimate is failed, as ndt-d2d.
constexpr long kMrsmapMinTerms = 20;

RegistrationResult mrsmap_solve(const RegistrationOptions& options, const NdtSamples& cur, const NdtSamples& ref,
                         const SE3& T0) {
  const MrsmapOptions& o = options.method_as<MrsmapOptions>();
  const std::vector<SurfelLevel> cur_map = surfel_map(cur, o);
  const std::vector<SurfelLevel> ref_map = surfel_map(ref, o);
  const NdtSolveOptions so =
      ndt_solve_options(options, cur.points, double(cur_map.back().grid.size()), kMrsmapMinTerms);
  const std::vector<NdtLevel> levels = surfel_levels(cur_map, ref_map, o.descriptor_max_distance);
  const SE3 T_lm = levenberg_marquardt(levels, o.lm_iterations, T0, so, options.driver);
  return solve_ndt(levels, so, options.driver, T0, &T_lm);
}

RegistrationOptions mrsmap_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {10, 10, 10, 10};  // Newton per resolution, [0] the finest (0.05 m), as ndt-d2d
  auto mrsmap = std::make_unique<MrsmapOptions>();
  mrsmap->resolutions_mm = {400, 200, 100, 50};  // ndt-d2d's: surfels are its cells with colour and descriptors
  return RegistrationOptions(driver, std::move(mrsmap));
}

std::unique_ptr<Registration> make_mrsmap(const RegistrationOptions& options, std::unique_ptr<ReductionBackend>) {
  return make_ndt_registration("mrsmap", options, mrsmap_solve, /*reads_colour=*/true);
}

}  // namespace

RegistrationMethod mrsmap_registration_method() { return {"mrsmap", mrsmap_defaults, make_mrsmap}; }

}  // namespace hf
