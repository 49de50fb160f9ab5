// How this process was started, for reports (report.json "command_line", "started_utc"): recorded once by main()
// before parsing, read by the subcommands. Not thread-safe to record; safe to read afterwards.
#pragma once

#include <string>

namespace hf::apps {

// Records argv (shell-quoted where an argument needs it, so the line can be pasted back) and the time.
void record_invocation(int argc, const char* const* argv);
const std::string& invocation_command_line();  // "" before record_invocation
const std::string& invocation_started_utc();   // ISO 8601 UTC, "2026-12-06T22:37:36Z"; "" before

// `text` as one shell word: unchanged when it holds only [A-Za-z0-9_./:=,+@%-], else in single quotes.
std::string shell_word(const std::string& text);

}  // namespace hf::apps
