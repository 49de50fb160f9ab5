// Differential attribute profile over second-generation openings (Cvirn section 4.1): with area thresholds
// a1 < a2 < a3 and Gamma_k = Gamma^psi_(A,a_k)(S),
//   hamlets S^H = S \ Gamma_1,  villages S^V = Gamma_1 \ Gamma_2,  towns S^T = Gamma_2 \ Gamma_3,  cities S^C = Gamma_3.
// Because the openings of one psi(S) are nested, a cell of S lands in exactly one class: the one whose interval
// [a_k, a_{k+1}) holds the area of its cluster (its component of psi(S)). That is how it is computed (one
// labelling instead of three openings); tests check it against the set differences above.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include "lidar/connected_components.h"

namespace hf::lidar {

enum class BuiltUpClass : std::uint8_t { none = 0, hamlet = 1, village = 2, town = 3, city = 4 };
constexpr int kBuiltUpClasses = 4;  // hamlet..city
const char* class_name(BuiltUpClass c);  // "hamlet", ..., "none"

struct AreaThresholds {
  // The paper's values (m^2); it calls them intuitive, there being no standard definition of the terms.
  double a1 = 50000, a2 = 1000000, a3 = 5000000;
};
// Throws hf::Error unless 0 < a1 < a2 < a3, all finite.
void validate(const AreaThresholds& a);

// The class of a cluster of psi(S) with this area.
BuiltUpClass class_of_area(double area_m2, const AreaThresholds& a);

struct ClassStatistics {
  std::int64_t cells = 0;        // cells of S in the class
  std::int64_t components = 0;   // buildings: components C_i of S in the class
  std::int64_t settlements = 0;  // clusters: components of psi(S) in the class
};

struct Profile {
  Image<std::uint8_t> classes;  // BuiltUpClass per cell; none outside S
  std::array<ClassStatistics, kBuiltUpClasses> stats;  // index = class - 1
};

// The profile of S given psi(S) (psi_s ⊇ s).
Profile differential_profile(const Mask& s, const Mask& psi_s, const AreaThresholds& a, double cell_m);

}  // namespace hf::lidar
