#include "core/error.h"

namespace hf {

ParseError::ParseError(const std::string& file, int line, const std::string& message)
    : Error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + message), file_(file), line_(line) {}

std::string quote_for_message(std::string_view s) {
  constexpr size_t kMaxQuoted = 40;
  std::string out = "'";
  for (size_t i = 0; i < s.size() && i < kMaxQuoted; ++i) {
    const unsigned char c = static_cast<unsigned char>(s[i]);
    out += (c >= 32 && c < 127) ? static_cast<char>(c) : '?';
  }
  if (s.size() > kMaxQuoted) out += "...";
  return out + "'";
}

}  // namespace hf
