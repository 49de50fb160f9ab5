// Fuzz target: results.csv as the harness reads it back must give rows or throw hf::Error naming the file and line,
// never crash or trip a sanitizer.
#include <cstddef>
#include <cstdint>
#include <string>

#include "bench/harness/results.h"
#include "core/error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  try {
    const auto rows = hf::bench::results_from_csv(std::string(reinterpret_cast<const char*>(data), size), "fuzz.csv");
    (void)rows.size();
  } catch (const hf::Error&) {
  }
  return 0;
}
