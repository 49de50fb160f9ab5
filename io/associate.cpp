#include "io/associate.h"

#include <algorithm>
#include <cmath>
#include <tuple>

namespace hf {

std::vector<Match> associate(const std::vector<double>& a, const std::vector<double>& b,
                             const AssociationOptions& options) {
  struct Candidate {
    double diff;
    size_t a, b;
  };
  std::vector<Candidate> candidates;
  size_t lo = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    // b is sorted, so the b within max_difference of a[i] form one window that only moves forward.
    while (lo < b.size() && b[lo] + options.offset_s <= a[i] - options.max_difference_s) ++lo;
    for (size_t j = lo; j < b.size() && b[j] + options.offset_s < a[i] + options.max_difference_s; ++j) {
      const double d = std::fabs(a[i] - (b[j] + options.offset_s));
      if (d < options.max_difference_s) candidates.push_back({d, i, j});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& x, const Candidate& y) {
    return std::tie(x.diff, x.a, x.b) < std::tie(y.diff, y.a, y.b);
  });
  std::vector<char> used_a(a.size(), 0), used_b(b.size(), 0);
  std::vector<Match> matches;
  for (const Candidate& c : candidates) {
    if (used_a[c.a] || used_b[c.b]) continue;
    used_a[c.a] = used_b[c.b] = 1;
    matches.push_back({c.a, c.b});
  }
  std::sort(matches.begin(), matches.end(), [](const Match& x, const Match& y) { return x.a < y.a; });
  return matches;
}

}  // namespace hf
