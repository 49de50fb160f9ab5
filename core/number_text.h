// Numbers from untrusted input, printed short in messages whatever their size.
#pragma once

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <system_error>

namespace hf {

// Six significant digits ("%.6g": 1e+300, 0.0125, 2.5e+07), "inf" and "nan" as such: std::to_string(1e300) prints
// 301 digits and a fixed decimal point, a message no one can read.
inline std::string number_for_message(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

// The double whose shortest decimal form is the float's: 0.1f becomes 0.1, not 0.10000000149011612, so a float
// written into JSON (which holds doubles, printed shortest-round-trip) reads as the value that was set, and reads
// back into the same float.
inline double float_as_shortest_double(float value) {
  char buffer[32];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer - 1, value);
  if (r.ec != std::errc()) return double(value);
  *r.ptr = '\0';
  return std::strtod(buffer, nullptr);
}

}  // namespace hf
