#include "head/curvature.h"

#include <cmath>

namespace hf::head {

void VertexCurvatures::resize(int n, bool with_directions) {
  mean.assign(n, 0.0f);
  gaussian.assign(n, 0.0f);
  k_max.assign(n, 0.0f);
  k_min.assign(n, 0.0f);
  valid.assign(n, 0);
  dir_max.assign(with_directions ? n : 0, Eigen::Vector3f::Zero());
  dir_min.assign(with_directions ? n : 0, Eigen::Vector3f::Zero());
  valid_count = 0;
}

void principal_from_mean_gaussian(double H, double K, double* k_max, double* k_min) {
  const double disc = H * H - K;
  const double root = disc > 0.0 ? std::sqrt(disc) : 0.0;
  *k_max = H + root;
  *k_min = H - root;
}

}  // namespace hf::head
