// Line-based reading shared by the photogrammetry text parsers (OpenMVS dumps, Middlebury *_par.txt): lines longer
// than kMaxLineBytes are refused, '#' lines and blank lines are skipped, numbers are whole tokens, finite, and
// quoted with quote_for_message in errors. Every error is hf::ParseError "FILE:LINE: expected ...".
#pragma once

#include <charconv>
#include <cmath>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

#include "core/bounded_read.h"
#include "core/error.h"
#include "io/text_util.h"

namespace hf::photogrammetry::detail {

// Calls line(words, line_number) for every non-blank, non-comment line of `text`.
inline void for_each_data_line(const std::string& text, const std::string& file,
                               const std::function<void(const std::vector<std::string_view>&, int)>& line) {
  int lineno = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view l(text.data() + pos, end - pos);
    pos = end + 1;
    ++lineno;
    if (l.size() > kMaxLineBytes)
      throw ParseError(file, lineno, "expected a line of at most " + std::to_string(kMaxLineBytes) + " bytes, got " +
                                         std::to_string(l.size()));
    const std::vector<std::string_view> words = split_words(l);
    if (words.empty() || words[0][0] == '#') continue;
    line(words, lineno);
  }
}

inline double parse_double(std::string_view word, const std::string& file, int line, const char* what) {
  double v = 0;
  const char* begin = word.data() + (!word.empty() && word[0] == '+' ? 1 : 0);
  const auto [end, ec] = std::from_chars(begin, word.data() + word.size(), v);
  if (word.empty() || ec != std::errc() || end != word.data() + word.size() || !std::isfinite(v))
    throw ParseError(file, line, std::string("expected a finite number (") + what + "), got " +
                                     quote_for_message(word));
  return v;
}

inline long long parse_integer(std::string_view word, const std::string& file, int line, const char* what,
                               long long lo, long long hi) {
  long long v = 0;
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), v);
  if (word.empty() || ec != std::errc() || end != word.data() + word.size() || v < lo || v > hi)
    throw ParseError(file, line, std::string("expected an integer in [") + std::to_string(lo) + ", " +
                                     std::to_string(hi) + "] (" + what + "), got " + quote_for_message(word));
  return v;
}

}  // namespace hf::photogrammetry::detail
