#include "lidar/differential_profile.h"

#include <cmath>
#include <vector>

#include "core/error.h"

namespace hf::lidar {

const char* class_name(BuiltUpClass c) {
  switch (c) {
    case BuiltUpClass::hamlet: return "hamlet";
    case BuiltUpClass::village: return "village";
    case BuiltUpClass::town: return "town";
    case BuiltUpClass::city: return "city";
    default: return "none";
  }
}

void validate(const AreaThresholds& a) {
  if (!(std::isfinite(a.a1) && std::isfinite(a.a2) && std::isfinite(a.a3) && a.a1 > 0 && a.a1 < a.a2 && a.a2 < a.a3))
    throw Error("area thresholds must satisfy 0 < a1 < a2 < a3 (m^2)");
}

BuiltUpClass class_of_area(double area_m2, const AreaThresholds& a) {
  if (area_m2 < a.a1) return BuiltUpClass::hamlet;
  if (area_m2 < a.a2) return BuiltUpClass::village;
  if (area_m2 < a.a3) return BuiltUpClass::town;
  return BuiltUpClass::city;
}

Profile differential_profile(const Mask& s, const Mask& psi_s, const AreaThresholds& a, double cell_m) {
  validate(a);
  if (s.width() != psi_s.width() || s.height() != psi_s.height()) throw Error("differential_profile: psi(S) size differs from S");
  const Components clusters = connected_components(psi_s);
  const Components buildings = connected_components(s);
  std::vector<BuiltUpClass> cluster_class(static_cast<size_t>(clusters.count));
  for (int i = 0; i < clusters.count; ++i) cluster_class[i] = class_of_area(double(clusters.cells[i]) * cell_m * cell_m, a);

  Profile p;
  p.classes = Image<std::uint8_t>(s.width(), s.height(), 0);
  std::vector<char> building_seen(static_cast<size_t>(buildings.count), 0), cluster_seen(static_cast<size_t>(clusters.count), 0);
  for (size_t i = 0; i < s.size(); ++i) {
    if (!s.pixels()[i]) continue;
    const int k = clusters.label.pixels()[i];
    if (k < 0) throw Error("differential_profile: psi(S) is not a superset of S");
    const BuiltUpClass c = cluster_class[k];
    p.classes.pixels()[i] = static_cast<std::uint8_t>(c);
    ClassStatistics& st = p.stats[static_cast<int>(c) - 1];
    ++st.cells;
    if (char& seen = building_seen[buildings.label.pixels()[i]]; !seen) seen = 1, ++st.components;
    if (char& seen = cluster_seen[k]; !seen) seen = 1, ++st.settlements;
  }
  return p;
}

}  // namespace hf::lidar
