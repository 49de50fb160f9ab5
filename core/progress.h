// Progress for long work. On a terminal: one redrawn line with a bar, rate, ETA and a status word. Elsewhere
// (CI logs, pipes): a plain line every `plain_every_s` seconds and at the end, so logs stay readable.
//
//   Progress p("tracking", total_frames);
//   for (...) { ...; p.update(i + 1, "good"); }
//   p.finish();
//
// Writes to stderr. Not thread-safe: call from one thread.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace hf {

class Progress {
 public:
  Progress(std::string label, long total, double plain_every_s = 5.0, std::FILE* out = stderr);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  void update(long done, const std::string& status = "");
  void finish();  // final line; idempotent

  // The line drawn for `done` items after `elapsed_s` seconds (exposed for tests).
  static std::string format(const std::string& label, long done, long total, double elapsed_s,
                            const std::string& status, int bar_width);

 private:
  std::string label_;
  long total_;
  long done_ = 0;
  double plain_every_s_;
  std::FILE* out_;
  bool tty_;
  bool finished_ = false;
  std::string status_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  void draw(bool final_line);
};

}  // namespace hf
