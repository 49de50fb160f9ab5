// "combined, gicp, icp, ...": every registration method (registration_names(), sorted) for the --help of run and
// bench, so the synopsis lists all of them and cannot fall behind the registry.
#pragma once

#include <string>

#include "registration/registration.h"

namespace hf::apps {

inline std::string registration_list() {
  std::string names;
  for (const std::string& n : registration_names()) names += (names.empty() ? "" : ", ") + n;
  return names;
}

}  // namespace hf::apps
