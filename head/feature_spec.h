// Parsers for the user-typed settings of `hashfusion head-features` (untrusted text; fuzzed by
// tests/head/fuzz_feature_spec.cpp). Each throws hf::Error with one line naming the option and what was expected.
//   parse_threshold("a,b")              -> [a, b] in eq. 10's percent, -100 <= a <= b <= 100, finite
//   parse_morphology("open:5,dilate:10") -> steps applied left to right; op in dilate|erode|open|close,
//                                          k an integer in 0..1000; "" or "none" -> no steps
//   parse_evaluation("discrete" | "mls" | "laplace") and the quantity ("mean" | "gaussian" | "k_max" | "k_min")
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "head/morphology.h"

namespace hf::head {

enum class Evaluation { discrete, mls, laplace };
enum class Quantity { mean, gaussian, k_max, k_min };

struct ThresholdRange {
  float a = 0, b = 100;
};

ThresholdRange parse_threshold(std::string_view text);
std::vector<MorphologyStep> parse_morphology(std::string_view text);
Evaluation parse_evaluation(std::string_view text);
Quantity parse_quantity(std::string_view text);
const char* evaluation_name(Evaluation e);
const char* quantity_name(Quantity q);

}  // namespace hf::head
