#include "registration/ndt/ndt_options.h"

#include <algorithm>
#include <cmath>

#include "registration/gauss_newton.h"

namespace hf {

void NdtOptions::visit(OptionVisitor& v) {
  v("resolutions_mm", resolutions_mm);
  v("outlier_ratio", outlier_ratio);
  v("point_stride", point_stride);
  v("neighbours", neighbours);
  v("min_cell_points", grid.min_points);
  v("eigenvalue_floor_ratio", grid.eigenvalue_floor_ratio);
  v("min_sigma_m", grid.min_sigma_m);
}

void NdtOptions::validate() const {
  require_option(!resolutions_mm.empty() && resolutions_mm.size() <= 8, "resolutions_mm must have 1..8 entries");
  for (const int r : resolutions_mm) require_option(r >= 10 && r <= 10000, "resolutions_mm must be in 10..10000");
  require_option(outlier_ratio > 0.0 && outlier_ratio < 1.0, "outlier_ratio must be in (0, 1)");
  require_option(point_stride >= 1 && point_stride <= 16, "point_stride must be in 1..16");
  require_option(neighbours == 1 || neighbours == 7, "neighbours must be 1 or 7");
  require_option(grid.min_points >= 3, "min_cell_points must be >= 3");
  require_option(grid.eigenvalue_floor_ratio > 0.0 && grid.eigenvalue_floor_ratio < 1.0,
                 "eigenvalue_floor_ratio must be in (0, 1)");
  require_option(finite_positive(grid.min_sigma_m), "min_sigma_m must be finite and > 0");
}

std::vector<double> NdtOptions::resolutions_m() const {
  std::vector<double> r;
  for (const int mm : resolutions_mm) r.push_back(mm * 1e-3);
  return r;
}

RegistrationResult ndt_align_checked(const FramePyramid& current, const FramePyramid& reference,
                                     const SE3& T_initial, const RegistrationOptions& reg_options,
                                     const NdtAlign& align) {
  const NdtOptions& options = reg_options.method_as<NdtOptions>();
  RegistrationResult r;
  r.T_ref_cur = T_initial.is_finite() ? T_initial : SE3();
  r.iterations_per_level.assign(options.resolutions_mm.size(), 0);
  if (!T_initial.is_finite()) {
    r.status = RegistrationStatus::failed;
    r.message = "the initial guess is not finite";
    return r;
  }
  if (current.num_levels() < 1 || reference.num_levels() < 1) {
    r.status = RegistrationStatus::no_data;
    r.message = "empty pyramid";
    return r;
  }
  const long needed = options.grid.min_points;
  const NdtSamples cur = sample_ndt(current.levels[0], options.point_stride);
  const NdtSamples ref = sample_ndt(reference.levels[0], options.point_stride);
  if (long(cur.points.size()) < needed || long(ref.points.size()) < needed) {
    r.status = RegistrationStatus::no_data;
    r.message = std::string("too few valid points in the ") +
                (long(cur.points.size()) < needed ? "current" : "reference") + " frame";
    return r;
  }
  try {
    RegistrationResult result = align(cur, ref, T_initial);
    if (result.usable()) {
      verify_large_motion(
          reg_options.driver, T_initial, [&](const SE3& T_reverse) { return align(ref, cur, T_reverse); }, result);
    }
    return result;
  } catch (const std::exception& e) {
    r.status = RegistrationStatus::failed;
    r.message = std::string("registration error: ") + e.what();
  }
  return r;
}

namespace {

class NdtRegistration final : public Registration {
 public:
  NdtRegistration(std::string name, const RegistrationOptions& options, NdtSolve solve, bool reads_colour)
      : name_(std::move(name)), options_(options), solve_(solve), reads_colour_(reads_colour) {
    options_.validate();
  }
  RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                           const SE3& T_ref_cur_initial) override {
    return ndt_align_checked(current, reference, T_ref_cur_initial, options_,
                             [&](const NdtSamples& cur, const NdtSamples& ref, const SE3& T0) {
                               return solve_(options_, cur, ref, T0);
                             });
  }
  std::string name() const override { return name_; }
  const RegistrationOptions& options() const override { return options_; }
  bool reads_colour() const override { return reads_colour_; }

 private:
  std::string name_;
  RegistrationOptions options_;
  NdtSolve solve_;
  bool reads_colour_;
};

}  // namespace

std::unique_ptr<Registration> make_ndt_registration(const std::string& name, const RegistrationOptions& options,
                                                    NdtSolve solve, bool reads_colour) {
  return std::make_unique<NdtRegistration>(name, options, solve, reads_colour);
}

NdtSolveOptions ndt_solve_options(const RegistrationOptions& options, const std::vector<Eigen::Vector3d>& current,
                                  double rows_possible, long min_terms) {
  NdtSolveOptions so;
  so.iterations = options.driver.iterations;
  so.outlier_ratio = options.method_as<NdtOptions>().outlier_ratio;
  so.min_terms = min_terms;
  so.rows_possible = rows_possible;
  so.unit_scale = point_units(current);
  return so;
}

Vector6d point_units(const std::vector<Eigen::Vector3d>& points) {
  double sum_sq = 0.0;
  for (const Eigen::Vector3d& p : points) sum_sq += p.squaredNorm();
  const double L = std::max(1e-3, std::sqrt(sum_sq / double(std::max<size_t>(1, points.size()))));
  Vector6d s;
  s << 1.0 / L, 1.0 / L, 1.0 / L, 1.0, 1.0, 1.0;
  return s;
}

NdtSamples sample_ndt(const FramePyramidLevel& level, int stride) {
  NdtSamples samples;
  const bool colour = level.has_intensity() && level.intensity.width() == level.vertices.width() &&
                      level.intensity.height() == level.vertices.height();
  for (int y = 0; y < level.vertices.height(); y += stride) {
    for (int x = 0; x < level.vertices.width(); x += stride) {
      const hf_float4& v = level.vertices(x, y);
      if (v.w == 0.0f || !std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) continue;
      const float c = colour ? level.intensity(x, y) : 0.0f;
      if (colour && !std::isfinite(c)) continue;
      samples.points.emplace_back(v.x, v.y, v.z);
      if (colour) samples.intensity.push_back(double(c));
    }
  }
  return samples;
}

}  // namespace hf
