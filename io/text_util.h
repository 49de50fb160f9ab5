// Small text helpers shared by the io parsers (PLY, OBJ): untrusted input is split the same way everywhere and
// quoted with core/error.h's quote_for_message, so error messages look alike and stay printable.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "core/error.h"

namespace hf {

// The words of one line, separated by spaces, tabs and carriage returns (CRLF files read like LF files).
// The views point into `line`.
inline std::vector<std::string_view> split_words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  auto space = [&](size_t k) { return line[k] == ' ' || line[k] == '\t' || line[k] == '\r'; };
  while (i < line.size()) {
    while (i < line.size() && space(i)) ++i;
    const size_t start = i;
    while (i < line.size() && !space(i)) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

}  // namespace hf
