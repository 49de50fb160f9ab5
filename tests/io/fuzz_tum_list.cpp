// Fuzzes the TUM rgb.txt / depth.txt parser: any input either parses into sorted, finite, distinct stamps with
// non-empty names, or throws hf::ParseError with a short printable message. Anything else (crash, other exception)
// is a finding. A first line over the length limit is always refused on line 1.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "io/tum_dataset.h"
#include "tests/io/fuzz_message_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const auto entries = hf::parse_tum_list(text, "fuzz.txt");
    for (size_t i = 0; i < entries.size(); ++i) {
      if (!std::isfinite(entries[i].timestamp_s) || entries[i].file.empty() || entries[i].line < 1) std::abort();
      if (i > 0 && !(entries[i - 1].timestamp_s < entries[i].timestamp_s)) std::abort();
    }
  } catch (const hf::ParseError& e) {
    if (e.file() != "fuzz.txt" || e.line() < 1) std::abort();
    hf::fuzz::check_message(e, "fuzz.txt");
  }
  hf::fuzz::check_long_first_line_refused(text, [](const std::string& t) { hf::parse_tum_list(t, "long.txt"); });
  return 0;
}
