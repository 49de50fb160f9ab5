#include "core/progress.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <iomanip>

namespace hf {

Progress::Progress(std::string label, long total, double plain_every_s, std::FILE* out)
    : label_(std::move(label)),
      total_(total),
      plain_every_s_(plain_every_s),
      out_(out),
      tty_(::isatty(::fileno(out)) != 0),
      start_(std::chrono::steady_clock::now()),
      last_draw_(start_) {}

Progress::~Progress() { finish(); }

std::string Progress::format(const std::string& label, long done, long total, double elapsed_s,
                             const std::string& status, int bar_width) {
  std::ostringstream s;
  s << label << " ";
  if (bar_width > 0 && total > 0) {
    const int filled = int(std::lround(bar_width * std::clamp(double(done) / double(total), 0.0, 1.0)));
    s << "[" << std::string(size_t(filled), '#') << std::string(size_t(bar_width - filled), '.') << "] ";
  }
  s << done;
  if (total > 0) s << "/" << total;
  const double rate = elapsed_s > 0 ? double(done) / elapsed_s : 0.0;
  s << std::fixed << std::setprecision(1) << " " << rate << "/s";
  if (total > 0 && rate > 0 && done < total) s << " eta " << std::setprecision(0) << double(total - done) / rate << "s";
  if (!status.empty()) s << " " << status;
  return s.str();
}

void Progress::update(long done, const std::string& status) {
  done_ = done;
  status_ = status;
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_draw_).count();
  // Redraw a terminal at most ~10 times a second; plain output only every plain_every_s_.
  if ((tty_ && since >= 0.1) || (!tty_ && since >= plain_every_s_)) {
    last_draw_ = now;
    draw(false);
  }
}

void Progress::finish() {
  if (finished_) return;
  finished_ = true;
  draw(true);
}

void Progress::draw(bool final_line) {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const std::string line = format(label_, done_, total_, elapsed, status_, tty_ ? 30 : 0);
  if (tty_) {
    std::fprintf(out_, "\r\033[K%s%s", line.c_str(), final_line ? "\n" : "");
  } else {
    std::fprintf(out_, "%s\n", line.c_str());
  }
  std::fflush(out_);
}

}  // namespace hf
