#include "apps/invocation.h"

#include <chrono>
#include <ctime>

namespace hf::apps {
namespace {

struct Invocation {
  std::string command_line, started_utc;
};

Invocation& invocation() {
  static Invocation i;
  return i;
}

}  // namespace

std::string shell_word(const std::string& text) {
  bool plain = !text.empty();
  for (char c : text)
    if (!((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
          std::string("_./:=,+@%-").find(c) != std::string::npos))
      plain = false;
  if (plain) return text;
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

void record_invocation(int argc, const char* const* argv) {
  std::string line;
  for (int i = 0; i < argc; ++i) {
    // argv[0] as its file name: the install path says nothing about the run and may hold a home folder.
    std::string word = argv[i];
    if (i == 0) word = word.substr(word.find_last_of('/') == std::string::npos ? 0 : word.find_last_of('/') + 1);
    line += (i ? " " : "") + shell_word(word);
  }
  const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm utc{};
  gmtime_r(&now, &utc);
  char date[32];
  std::strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", &utc);
  invocation() = {line, date};
}

const std::string& invocation_command_line() { return invocation().command_line; }
const std::string& invocation_started_utc() { return invocation().started_utc; }

}  // namespace hf::apps
