// Errors that carry where they happened. The CLI prints what() as one line on stderr and exits non-zero.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

namespace hf {

// Any failure a user can act on: missing file, bad argument, unsupported format.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Malformed input in a file: what() reads "FILE:LINE: expected ..., got '...'" (line 0 = whole file).
class ParseError : public Error {
 public:
  ParseError(const std::string& file, int line, const std::string& message);
  const std::string& file() const { return file_; }
  int line() const { return line_; }

 private:
  std::string file_;
  int line_;
};

// (A prefix of) untrusted text for a message, the one way every parser quotes input: printable ASCII only ('?' for
// the rest, so no terminal escape sequence reaches the terminal), at most 40 characters (then "..."), in single
// quotes. A 10 MB token yields a 45-character quote.
std::string quote_for_message(std::string_view text);

}  // namespace hf
