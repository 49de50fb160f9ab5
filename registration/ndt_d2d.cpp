#include "registration/ndt_d2d.h"

#include "registration/gauss_newton.h"
#include "registration/ndt/ndt_newton.h"

namespace hf {
namespace {

// For each level (coarsest first), the current Gaussians (means moved by T) against the reference's around T mu.
std::vector<NdtLevel> d2d_levels(const NdtModel& current, const NdtModel& reference) {
  std::vector<NdtLevel> levels;
  for (size_t l = 0; l < reference.levels.size() && l < current.levels.size(); ++l) {
    const NdtGrid& cur = current.levels[l];
    const NdtGrid& ref = reference.levels[l];
    NdtLevel level;
    level.cell_m = ref.cell_m();
    level.associate = [&cur, &ref](const SE3& T, std::vector<NdtTerm>* terms) {
      terms->clear();
      std::vector<const NdtCell*> cells;
      const Eigen::Matrix3d R = T.rotation();
      for (const NdtCell& c : cur.cells()) {
        ref.neighbourhood(R * c.mean + T.translation(), 7, &cells);
        NdtTerm term;
        for (const NdtCell* r : cells) {
          if (distribution_term(c, *r, R, ref.cell_m(), &term)) terms->push_back(term);
        }
      }
    };
    levels.push_back(std::move(level));
  }
  return levels;
}

// Cell pairs at the finest level below which the estimate is failed: a 0.1 m model of a room view has ~500 cells.
constexpr long kNdtD2dMinTerms = 20;

RegistrationResult ndt_d2d_solve(const RegistrationOptions& options, const NdtSamples& cur, const NdtSamples& ref,
                         const SE3& T0) {
  const NdtOptions& o = options.method_as<NdtOptions>();
  const NdtModel cur_model = build_ndt_model(cur.points, o.resolutions_m(), o.grid);
  const NdtModel ref_model = build_ndt_model(ref.points, o.resolutions_m(), o.grid);
  const NdtSolveOptions so =
      ndt_solve_options(options, cur.points, double(cur_model.levels.back().size()), kNdtD2dMinTerms);
  return solve_ndt(d2d_levels(cur_model, ref_model), so, options.driver, T0);
}

RegistrationOptions ndt_d2d_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {10, 10, 10, 10};  // per resolution, [0] the finest (0.05 m)
  auto ndt = std::make_unique<NdtOptions>();
  // A 0.05 m level below the three: with 0.1 m cells the moved means settle 4.4 mm / 0.15 deg off on the
  // noisy room pair (test_accuracy.cpp), where p2d's points reach 1.5 mm.
  ndt->resolutions_mm = {400, 200, 100, 50};
  return RegistrationOptions(driver, std::move(ndt));
}

std::unique_ptr<Registration> make_ndt_d2d(const RegistrationOptions& options, std::unique_ptr<ReductionBackend>) {
  return make_ndt_registration("ndt-d2d", options, ndt_d2d_solve);
}

}  // namespace

RegistrationMethod ndt_d2d_registration_method() { return {"ndt-d2d", ndt_d2d_defaults, make_ndt_d2d}; }

}  // namespace hf
