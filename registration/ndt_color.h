// "ndt-color": colour NDT (Huhle, Magnusson, Strasser and Lilienthal 2008; report section 4.2, eq. 67-70).
// The reference frame's points are binned into the multi-resolution cells of registration/ndt/ndt_cells.h; the
// colours of each cell are modelled by a mixture of M Gaussians (k-means, then EM: eq. 67), and each component j
// weighs the cell's points by its colour kernel w_j(c) = exp(-(c - mu*_j)^2 / (2 sigma*_j^2)) (eq. 68) into a
// spatial Gaussian of its own. A current point with colour c at T p is scored against the components of its cell
// (and, with neighbours = 7, of its face neighbours) by s = -sum_i sum_j w_j(c_i) p_j(T p_i) (eq. 69-70), in
// Magnusson's Gaussian approximation, minimised by the Newton solver of registration/ndt/ndt_newton.h coarse to
// fine (which also states how degeneracy is judged).
//
// Colour: the pyramid's intensity ([0, 1], core/image.h), so the colour space is one-dimensional (Huhle's L*a*b*
// reduced to its lightness); the mixture and the kernel are written for that space. A frame without colour is
// no_data.
#pragma once

#include "registration/ndt/ndt_options.h"

namespace hf {

struct NdtColorOptions : NdtOptions {
  // Mixture components per cell: Huhle's M = 3 (fewer where the cell's colours do not separate: components whose
  // means are within min_colour_sigma merge).
  int colour_components = 3;
  int em_iterations = 5;            // after 5 of k-means from the colour quantiles
  // NdtOptions::neighbours stays ndt-p2d's 7 (Magnusson's neighbourhood, for the basin). On the noisy room pair 1
  // (the point's cell only) gives 0.93 mm in a quarter of the time; untried on real data, so not the default.
  // Floor of a component's colour sigma (intensity units): 0.03 ~ 8 grey levels, above the synthetic and Kinect
  // colour noise, so a flat-coloured cell keeps a kernel as wide as the noise. On the noisy room pair of
  // tests/registration/test_accuracy.cpp 0.01 / 0.03 / 0.1 give 0.87 / 1.11 / 1.43 mm and M = 1 gives 1.63 mm
  // (ndt-p2d 1.53 mm); 0.03 is kept for real colour noise, which that pair does not model. The rest of the data:
  // bench/results/table1/README.md (ndt-color).
  double min_colour_sigma = 0.03;

  std::unique_ptr<MethodOptions> clone() const override { return std::make_unique<NdtColorOptions>(*this); }
  void visit(OptionVisitor& v) override;
  void validate() const override;
};

// One component of a cell's colour mixture (eq. 67): weight alpha, mean and variance in intensity units.
struct ColourComponent {
  double alpha = 1.0, mean = 0.0, var = 0.0;
};
// The mixture of `colours` (finite values): k-means from the quantiles, then EM, variances floored at
// min_sigma^2, close components merged; at most `components`, at least one for a non-empty input, none for an
// empty one. Deterministic.
std::vector<ColourComponent> colour_mixture(const std::vector<double>& colours, int components, int em_iterations,
                                            double min_sigma);

RegistrationMethod ndt_color_registration_method();

}  // namespace hf
