// Small text helpers shared by the io parsers (PLY, OBJ): untrusted input is split and quoted the same way
// everywhere, so error messages look alike and stay printable.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace hf {

// (A prefix of) untrusted text for an error message: printable ASCII only ('?' for the rest), at most 40
// characters (then "..."), in single quotes.
inline std::string quote_for_message(std::string_view s) {
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < 40; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (s.size() > 40) out += "...";
  return out + "'";
}

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
