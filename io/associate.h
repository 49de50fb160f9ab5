// Timestamp association exactly as TUM's associate.py.
//
// associate.py: every pair (a, b) with |a - (b + offset)| < max_difference is a candidate; candidates are sorted
// by that difference (ascending); they are taken greedily, each a and each b used at most once; the matches are
// returned sorted by a. Ties in the difference keep the order of (a index, b index), which makes the result
// deterministic where the Python script depends on list order.
#pragma once

#include <cstddef>
#include <vector>

namespace hf {

struct AssociationOptions {
  double max_difference_s = 0.02;
  double offset_s = 0.0;  // added to the second list's stamps before comparing
};

struct Match {
  size_t a = 0, b = 0;  // indices into the first and second list
};

// Both stamp lists must be sorted ascending (TUM files are; readers sort them). O((n + m) log) via a window
// search, not the script's O(n m), with the same result.
std::vector<Match> associate(const std::vector<double>& a_stamps, const std::vector<double>& b_stamps,
                             const AssociationOptions& options = {});

}  // namespace hf
