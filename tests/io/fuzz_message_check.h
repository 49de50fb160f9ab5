// What every parser's error message must be, checked by the fuzzers (issue 14.8): one line of printable ASCII
// (input is quoted with quote_for_message, core/error.h), short whatever the input, naming the file.
#pragma once

#include <cstdlib>
#include <string>

#include "core/error.h"

namespace hf::fuzz {

inline constexpr size_t kMaxMessageBytes = 400;

inline void check_message(const hf::Error& e, const std::string& file) {
  const std::string m = e.what();
  if (m.size() > kMaxMessageBytes || m.rfind(file, 0) != 0) std::abort();
  for (const char c : m)
    if (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126) std::abort();
}

// `text` with its first line padded past kMaxLineBytes (core/bounded_read.h): the fuzz inputs are shorter than the
// limit (-max_len=4096), so each input is also parsed this way to drive the limit's branch with fuzzed content.
inline std::string with_long_first_line(const std::string& text) { return std::string(4097, ' ') + text; }

}  // namespace hf::fuzz
