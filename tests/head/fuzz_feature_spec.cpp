// Fuzzes the head-features option parsers: any text either parses into values inside their documented ranges or
// raises hf::Error.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "core/error.h"
#include "head/feature_spec.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const hf::head::ThresholdRange t = hf::head::parse_threshold(text);
    if (!std::isfinite(t.a) || !std::isfinite(t.b) || t.a < -100 || t.b > 100 || t.a > t.b) std::abort();
  } catch (const hf::Error&) {
  }
  try {
    for (const hf::head::MorphologyStep& s : hf::head::parse_morphology(text))
      if (s.k < 0 || s.k > 1000) std::abort();
  } catch (const hf::Error&) {
  }
  try {
    hf::head::parse_evaluation(text);
  } catch (const hf::Error&) {
  }
  try {
    hf::head::parse_quantity(text);
  } catch (const hf::Error&) {
  }
  return 0;
}
