#include "registration/ndt_p2d.h"

#include "registration/gauss_newton.h"
#include "registration/ndt/ndt_newton.h"

namespace hf {
namespace {

// For each level (coarsest first), the current points against the reference's Gaussians around T p.
std::vector<NdtLevel> p2d_levels(const std::vector<Eigen::Vector3d>& points, const NdtModel& model,
                                 int neighbours) {
  std::vector<NdtLevel> levels;
  for (const NdtGrid& grid : model.levels) {
    NdtLevel level;
    level.cell_m = grid.cell_m();
    level.associate = [&points, &grid, neighbours](const SE3& T, std::vector<NdtTerm>* terms) {
      terms->clear();
      std::vector<const NdtCell*> cells;
      const Eigen::Matrix3d R = T.rotation();
      for (const Eigen::Vector3d& p : points) {
        grid.neighbourhood(R * p + T.translation(), neighbours, &cells);
        for (const NdtCell* c : cells) {
          terms->push_back({p, c->mean, c->Sigma_inv,
                            constraining_information(c->eigenvalues, c->eigenvectors, grid.cell_m()), 1.0});
        }
      }
    };
    levels.push_back(std::move(level));
  }
  return levels;
}

RegistrationResult ndt_p2d_solve(const RegistrationOptions& options, const NdtSamples& cur, const NdtSamples& ref,
                         const SE3& T0) {
  const NdtOptions& o = options.method_as<NdtOptions>();
  const NdtModel model = build_ndt_model(ref.points, o.resolutions_m(), o.grid);
  const NdtSolveOptions so =
      ndt_solve_options(options, cur.points, double(cur.points.size()), options.driver.min_inliers);
  return solve_ndt(p2d_levels(cur.points, model, o.neighbours), so, options.driver, T0);
}

RegistrationOptions ndt_p2d_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {10, 10, 10};  // per resolution, [0] the finest (0.1 m)
  // point_stride 2 (19200 points at 320x240, each against up to 7 cells): its cost, 290-350 ms of tracking per
  // fr1/rpy frame (bench/results/table1), buys the exact-data accuracy of test_accuracy.cpp (0.34 mm; every 4th
  // pixel: 0.84 mm, 0.03 deg).
  return RegistrationOptions(driver, std::make_unique<NdtOptions>());
}

std::unique_ptr<Registration> make_ndt_p2d(const RegistrationOptions& options, std::unique_ptr<ReductionBackend>) {
  return make_ndt_registration("ndt-p2d", options, ndt_p2d_solve);
}

}  // namespace

RegistrationMethod ndt_p2d_registration_method() { return {"ndt-p2d", ndt_p2d_defaults, make_ndt_p2d}; }

}  // namespace hf
