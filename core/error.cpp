#include "core/error.h"

namespace hf {

ParseError::ParseError(const std::string& file, int line, const std::string& message)
    : Error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + message), file_(file), line_(line) {}

}  // namespace hf
