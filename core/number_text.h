// Numbers from untrusted input, printed short in messages whatever their size.
#pragma once

#include <cstdio>
#include <string>

namespace hf {

// Six significant digits ("%.6g": 1e+300, 0.0125, 2.5e+07), "inf" and "nan" as such: std::to_string(1e300) prints
// 301 digits and a fixed decimal point, a message no one can read.
inline std::string number_for_message(double value) {
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%.6g", value);
  return buffer;
}

}  // namespace hf
