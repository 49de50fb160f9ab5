// Binary attribute openings with the area attribute A (Cvirn eq. 2) and their second-generation form (eq. 4):
//   Gamma_(A,a)(X)       keeps the 8-connected components C of X with A(C) >= a (m^2), removes the rest;
//   Gamma^psi_(A,a)(S) = Gamma_(A,a)(psi(S)) ∩ S, with psi the clustering operator (variant_dilation.h).
// The opening is anti-extensive, increasing and idempotent; the second-generation one is a subset of S.
#pragma once

#include "lidar/connected_components.h"

namespace hf::lidar {

Mask area_opening(const Mask& x, double a_m2, double cell_m);

// eq. 4 with psi(S) already computed (psi_s ⊇ s, same size).
Mask second_generation_opening(const Mask& s, const Mask& psi_s, double a_m2, double cell_m);

}  // namespace hf::lidar
