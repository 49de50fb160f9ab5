#include "registration/ndt_color.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "registration/gauss_newton.h"
#include "registration/ndt/ndt_newton.h"

namespace hf {

void NdtColorOptions::visit(OptionVisitor& v) {
  NdtOptions::visit(v);
  v("colour_components", colour_components);
  v("em_iterations", em_iterations);
  v("min_colour_sigma", min_colour_sigma);
}

void NdtColorOptions::validate() const {
  NdtOptions::validate();
  require_option(colour_components >= 1 && colour_components <= 8, "colour_components must be in 1..8");
  require_option(em_iterations >= 0 && em_iterations <= 100, "em_iterations must be in 0..100");
  require_option(finite_positive(min_colour_sigma) && min_colour_sigma < 1.0, "min_colour_sigma must be in (0, 1)");
}

namespace {

constexpr int kKmeansIterations = 5;
// Kernel weights below this are left out of a component's Gaussian and of the score (beyond 3 sigma: the term
// would add < 1 % of a matching one).
constexpr double kMinKernel = 0.01;

double kernel(double c, double mean, double var) { return std::exp(-0.5 * (c - mean) * (c - mean) / var); }

// Components sorted by mean; neighbours closer than min_sigma merged by their pooled moments.
std::vector<ColourComponent> merge_close(std::vector<ColourComponent> mix, double min_sigma) {
  std::sort(mix.begin(), mix.end(), [](const ColourComponent& a, const ColourComponent& b) { return a.mean < b.mean; });
  std::vector<ColourComponent> out;
  for (const ColourComponent& c : mix) {
    if (!(c.alpha > 0.0)) continue;
    if (!out.empty() && c.mean - out.back().mean < min_sigma) {
      ColourComponent& o = out.back();
      const double a = o.alpha + c.alpha;
      const double mean = (o.alpha * o.mean + c.alpha * c.mean) / a;
      const double second = (o.alpha * (o.var + o.mean * o.mean) + c.alpha * (c.var + c.mean * c.mean)) / a;
      o = {a, mean, std::max(second - mean * mean, min_sigma * min_sigma)};
    } else {
      out.push_back(c);
    }
  }
  return out;
}

}  // namespace

std::vector<ColourComponent> colour_mixture(const std::vector<double>& colours, int components, int em_iterations,
                                            double min_sigma) {
  std::vector<double> c;
  for (const double v : colours) {
    if (std::isfinite(v)) c.push_back(v);
  }
  if (c.empty() || components < 1) return {};
  std::vector<double> sorted = c;
  std::sort(sorted.begin(), sorted.end());
  const size_t n = c.size();
  const int M = int(std::min<size_t>(size_t(components), n));
  const double var_floor = min_sigma * min_sigma;
  std::vector<ColourComponent> mix(static_cast<size_t>(M));
  for (int j = 0; j < M; ++j) mix[size_t(j)].mean = sorted[(size_t(2 * j + 1) * n) / size_t(2 * M)];
  // k-means: hard assignment to the nearest mean (Huhle's initial guess for EM).
  std::vector<int> label(n, 0);
  auto nearest = [&](double v) {
    int best = 0;
    for (int j = 1; j < M; ++j) {
      if (std::abs(v - mix[size_t(j)].mean) < std::abs(v - mix[size_t(best)].mean)) best = j;
    }
    return best;
  };
  for (int it = 0; it <= kKmeansIterations; ++it) {
    std::vector<double> s(size_t(M), 0.0), ss(size_t(M), 0.0), count(size_t(M), 0.0);
    for (size_t k = 0; k < n; ++k) {
      label[k] = nearest(c[k]);
      s[size_t(label[k])] += c[k];
      ss[size_t(label[k])] += c[k] * c[k];
      count[size_t(label[k])] += 1.0;
    }
    for (size_t j = 0; j < size_t(M); ++j) {
      if (count[j] == 0.0) {
        mix[j].alpha = 0.0;
        continue;
      }
      mix[j].mean = s[j] / count[j];
      mix[j].var = std::max(ss[j] / count[j] - mix[j].mean * mix[j].mean, var_floor);
      mix[j].alpha = count[j] / double(n);
    }
  }
  // EM on the 1-D mixture (eq. 67); responsibilities in double, a point whose densities all underflow goes to its
  // nearest component.
  std::vector<double> r(static_cast<size_t>(M));
  for (int it = 0; it < em_iterations; ++it) {
    std::vector<double> sr(size_t(M), 0.0), src(size_t(M), 0.0), srcc(size_t(M), 0.0);
    for (size_t k = 0; k < n; ++k) {
      double total = 0.0;
      for (size_t j = 0; j < size_t(M); ++j) {
        r[j] = mix[j].alpha > 0.0 ? mix[j].alpha * kernel(c[k], mix[j].mean, mix[j].var) / std::sqrt(mix[j].var) : 0.0;
        total += r[j];
      }
      if (!(total > 0.0)) {
        std::fill(r.begin(), r.end(), 0.0);
        r[size_t(nearest(c[k]))] = total = 1.0;
      }
      for (size_t j = 0; j < size_t(M); ++j) {
        const double rj = r[j] / total;
        sr[j] += rj;
        src[j] += rj * c[k];
        srcc[j] += rj * c[k] * c[k];
      }
    }
    for (size_t j = 0; j < size_t(M); ++j) {
      if (!(sr[j] > 0.0)) {
        mix[j].alpha = 0.0;
        continue;
      }
      mix[j].alpha = sr[j] / double(n);
      mix[j].mean = src[j] / sr[j];
      mix[j].var = std::max(srcc[j] / sr[j] - mix[j].mean * mix[j].mean, var_floor);
    }
  }
  return merge_close(std::move(mix), min_sigma);
}

namespace {

// One resolution of the reference model: grid j holds component j of every cell's colour mixture, its spatial
// Gaussian from the cell's points weighted by the component's kernel (eq. 68) and its colour mean and variance.
std::vector<NdtGrid> colour_component_grids(const NdtSamples& ref, double cell_m, const NdtColorOptions& o) {
  std::vector<NdtGrid> grids(size_t(o.colour_components), NdtGrid(cell_m, o.grid));
  std::unordered_map<std::uint64_t, std::vector<int>> bins;
  for (size_t i = 0; i < ref.points.size(); ++i) {
    std::uint64_t key;
    if (grids[0].key_of(ref.points[i], &key)) bins[key].push_back(int(i));
  }
  std::vector<std::uint64_t> keys;
  for (const auto& [key, members] : bins) {
    if (long(members.size()) >= o.grid.min_points) keys.push_back(key);
  }
  std::sort(keys.begin(), keys.end());
  std::vector<double> colours;
  for (const std::uint64_t key : keys) {
    const std::vector<int>& members = bins[key];
    colours.clear();
    for (const int i : members) colours.push_back(ref.intensity[size_t(i)]);
    const std::vector<ColourComponent> mix =
        colour_mixture(colours, o.colour_components, o.em_iterations, o.min_colour_sigma);
    for (size_t j = 0; j < mix.size(); ++j) {
      NdtMoments m;
      for (const int i : members) {
        const double w = kernel(ref.intensity[size_t(i)], mix[j].mean, mix[j].var);
        if (w >= kMinKernel) m.add(ref.points[size_t(i)], w, ref.intensity[size_t(i)]);
      }
      NdtCell cell;
      if (!make_ndt_cell(m, o.grid, &cell)) continue;
      cell.colour_mean = mix[j].mean;
      cell.colour_var = mix[j].var;
      grids[j].insert(key, cell);
    }
  }
  return grids;
}

// For each level (coarsest first), each current point with its colour against the colour components of the
// reference cells around T p, weighted by the components' kernels at the point's colour (eq. 69).
std::vector<NdtLevel> colour_levels(const NdtSamples& cur, const std::vector<std::vector<NdtGrid>>& model,
                                    const std::vector<double>& cells_m, int neighbours) {
  std::vector<NdtLevel> levels;
  for (size_t l = 0; l < model.size(); ++l) {
    NdtLevel level;
    level.cell_m = cells_m[l];
    level.associate = [&cur, &grids = model[l], cell_m = cells_m[l], neighbours](const SE3& T,
                                                                               std::vector<NdtTerm>* terms) {
      terms->clear();
      std::vector<const NdtCell*> cells;
      const Eigen::Matrix3d R = T.rotation();
      for (size_t i = 0; i < cur.points.size(); ++i) {
        const Eigen::Vector3d x = R * cur.points[i] + T.translation();
        for (const NdtGrid& grid : grids) {
          grid.neighbourhood(x, neighbours, &cells);
          for (const NdtCell* c : cells) {
            const double w = kernel(cur.intensity[i], c->colour_mean, c->colour_var);
            if (w < kMinKernel) continue;
            terms->push_back({cur.points[i], c->mean, c->Sigma_inv,
                              constraining_information(c->eigenvalues, c->eigenvectors, cell_m), w});
          }
        }
      }
    };
    levels.push_back(std::move(level));
  }
  return levels;
}

RegistrationResult ndt_color_solve(const RegistrationOptions& options, const NdtSamples& cur, const NdtSamples& ref,
                         const SE3& T0) {
  const NdtColorOptions& o = options.method_as<NdtColorOptions>();
  if (!cur.has_intensity() || !ref.has_intensity()) {
    RegistrationResult r;
    r.T_ref_cur = T0;
    r.iterations_per_level.assign(o.resolutions_mm.size(), 0);
    r.status = RegistrationStatus::no_data;
    r.message = std::string("no colour in the ") + (cur.has_intensity() ? "reference" : "current") + " frame";
    return r;
  }
  const std::vector<double> cells_m = o.resolutions_m();
  std::vector<std::vector<NdtGrid>> model;
  for (const double cell_m : cells_m) model.push_back(colour_component_grids(ref, cell_m, o));
  const NdtSolveOptions so =
      ndt_solve_options(options, cur.points, double(cur.points.size()), options.driver.min_inliers);
  return solve_ndt(colour_levels(cur, model, cells_m, o.neighbours), so, options.driver, T0);
}

RegistrationOptions ndt_color_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {10, 10, 10};  // per resolution, [0] the finest (0.1 m), as ndt-p2d
  return RegistrationOptions(driver, std::make_unique<NdtColorOptions>());
}

std::unique_ptr<Registration> make_ndt_color(const RegistrationOptions& options, std::unique_ptr<ReductionBackend>) {
  return make_ndt_registration("ndt-color", options, ndt_color_solve, /*reads_colour=*/true);
}

}  // namespace

RegistrationMethod ndt_color_registration_method() { return {"ndt-color", ndt_color_defaults, make_ndt_color}; }

}  // namespace hf
