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

// Parses `text` with its first line padded past kMaxLineBytes (core/bounded_read.h) and aborts unless that line is
// refused, on line 1, naming the limit: the fuzz inputs are shorter than the limit (-max_len=4096), so each input is
// also parsed this way to drive the limit's branch with fuzzed content.
template <class Parse>
void check_long_first_line_refused(const std::string& text, Parse parse) {
  try {
    parse(std::string(4097, ' ') + text);
  } catch (const hf::ParseError& e) {
    if (e.line() == 1 && std::string(e.what()).find("expected a line of at most 4096 bytes") != std::string::npos)
      return;
  }
  std::abort();
}

}  // namespace hf::fuzz
