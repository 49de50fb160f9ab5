// "mrsmap": multi-resolution surfel maps (Stueckler and Behnke 2014; report section 4.4), on the shared
// multi-resolution cell model (registration/ndt/ndt_cells.h) in place of their octree: every cell of every
// resolution of both frames is a surfel, a Gaussian of shape with the mean and variance of its colour, and carries
// a shape-texture descriptor h (12 values, see surfel_descriptor) of its relations to the surfels of its 26
// neighbour cells. The score is D2D-NDT's (eq. 74-75: x' = T mu_cur - mu_ref, C = R Sigma_cur R^T + Sigma_ref)
// with its association (a current surfel moved by T against every reference surfel of the 7 cells around it: its
// cell and the face neighbours) restricted, as the report describes, to pairs whose descriptors are within
// descriptor_max_distance (L2); with the gate open it is ndt-d2d (test_registration_ndt). The nearest surfel alone
// (by mean, among 27 cells), tried first, pulls each surfel in-plane towards one neighbour's mean, as the two
// frames' grids cut a surface differently: 0.98 against 0.37 cm ATE over 30 frames of the room, 5.9 against 2.8
// cm on TUM fr1/rpy 0-29 (bench/results/table1/README.md). Optimisation as the report
// describes: Levenberg-Marquardt on the pairs' Mahalanobis distances, coarse to fine (lm_iterations per level),
// for the coarse pose, then Newton on the D2D score from there (registration/ndt/ndt_newton.h, which also states
// how degeneracy is judged and applies the driver's outcome rules against the initial guess).
//
// Colour: the pyramid's intensity (luminance), so the colour part of a surfel is one-dimensional and the texture
// half of the descriptor is the luminance difference to the neighbours. Without colour the texture bins all count
// "similar" and the method runs on shape. Normals point towards the frame's origin (its camera), so the
// descriptor is meant for frame-to-frame use. Left out: the octree's view-direction surfels (six per cell) and
// the per-point maximum resolution by depth; the keyframe graph and loop closure live in slam/.
#pragma once

#include <Eigen/Core>

#include "registration/ndt/ndt_options.h"

namespace hf {

struct MrsmapOptions : NdtOptions {
  // Descriptor gate (L2 over the four 3-bin histograms, each summing to 1: 0 equal, 2.83 disjoint). 1.0, chosen
  // on the noisy room pair of tests/registration/test_accuracy.cpp with the earlier nearest-surfel association:
  // 0.5 rejected 13 % of the pairs there and left the weakest direction below the degeneracy threshold; 1.0 kept
  // 94 % (4.5 mm, 0.20 deg); no gate 99 % (4.7 mm, 0.21 deg). With the 7-cell association it reads 3.7 mm there.
  // What it gives on the rest: bench/results/table1/README.md (mrsmap).
  double descriptor_max_distance = 1.0;
  double luminance_step = 0.05;  // |Delta luminance| above this: darker / brighter neighbour, else similar
  int lm_iterations = 5;         // Levenberg-Marquardt iterations per resolution before Newton
  // (NdtOptions::neighbours is not used: association always searches the 7 cells around a moved surfel.)

  std::unique_ptr<MethodOptions> clone() const override { return std::make_unique<MrsmapOptions>(*this); }
  void visit(OptionVisitor& v) override;
  void validate() const override;
};

// The shape-texture descriptor of `surfel` (a cell of `grid`), in the spirit of FPFH (Rusu et al. 2009): over the
// surfels t of its 26 neighbour cells, with the Darboux frame u = n_s, v = u x d / |u x d|, w = u x v
// (d = mu_t - mu_s normalised), the histograms of alpha = v . n_t and phi = u . d (3 bins over [-1, 1]) and of
// theta = atan2(w . n_t, u . n_t) (3 bins over [-pi, pi]), and of the luminance difference to t (darker, similar,
// brighter: luminance_step), each divided by the neighbours counted. All zero without neighbours. Normals point
// towards the origin.
using SurfelDescriptor = Eigen::Matrix<double, 12, 1>;
SurfelDescriptor surfel_descriptor(const NdtGrid& grid, const NdtCell& surfel, double luminance_step);

RegistrationMethod mrsmap_registration_method();

}  // namespace hf
