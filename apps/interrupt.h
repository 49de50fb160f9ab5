// Ctrl-C (SIGINT), SIGTERM (what `timeout`, systemd and batch schedulers send) and SIGHUP (a dropped ssh session or
// closed terminal) while a subcommand runs.
//
//   InterruptGuard guard;                         // installs the handlers; the destructor restores the old ones
//   control.stop = guard.flag();                  // the frame loop polls it and stops after the current frame
//   ... write every output ...
//   guard.exit_if_interrupted("outputs written for 12 frames");   // throws Interrupted: main() exits 130 / 143 / 129
//
// The handler only records the first signal and raises the flag, and it stays installed until the guard is
// destroyed, so a second Ctrl-C during the write phase cannot cut it short (each output is also written atomically,
// core/atomic_file.h). Exit status after an interruption is 128 + the signal (130 for SIGINT, 143 for SIGTERM, 129
// for SIGHUP: the terminal is gone, but the outputs for the work done are still wanted),
// so a script can tell an interrupted run, whose outputs are complete for the frames done, from a finished one.
// One guard at a time (the handlers are process-wide); not thread-safe to construct concurrently.
#pragma once

#include <atomic>
#include <csignal>
#include <stdexcept>
#include <string>

namespace hf::apps {

// Thrown after an interrupted command has written what it could; main() prints what() and exits 128 + signal.
class Interrupted : public std::runtime_error {
 public:
  Interrupted(int signal, const std::string& message) : std::runtime_error(message), signal_(signal) {}
  int signal() const { return signal_; }
  int exit_status() const { return 128 + signal_; }

 private:
  int signal_;
};

namespace detail {
inline std::atomic<bool> g_stop{false};
inline std::atomic<int> g_signal{0};
inline void on_stop_signal(int sig) {
  int none = 0;
  g_signal.compare_exchange_strong(none, sig);  // lock-free on every platform we build for: async-signal-safe
  g_stop.store(true);
}
}  // namespace detail

class InterruptGuard {
 public:
  InterruptGuard() {
    detail::g_stop.store(false);
    detail::g_signal.store(0);
    struct sigaction action {};
    action.sa_handler = detail::on_stop_signal;
    sigemptyset(&action.sa_mask);
    action.sa_flags = SA_RESTART;  // reads and writes in progress resume instead of failing with EINTR
    sigaction(SIGINT, &action, &previous_int_);
    sigaction(SIGTERM, &action, &previous_term_);
    sigaction(SIGHUP, &action, &previous_hup_);
  }
  ~InterruptGuard() {
    sigaction(SIGINT, &previous_int_, nullptr);
    sigaction(SIGTERM, &previous_term_, nullptr);
    sigaction(SIGHUP, &previous_hup_, nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

  const std::atomic<bool>* flag() const { return &detail::g_stop; }
  bool interrupted() const { return detail::g_stop.load(); }
  int signal() const { return detail::g_signal.load(); }  // the first signal received, 0 if none

  // Throws Interrupted("interrupted by SIGINT: " + what) when a signal arrived; does nothing otherwise.
  void exit_if_interrupted(const std::string& what) const {
    const int sig = signal();
    if (sig == 0) return;
    const char* name = sig == SIGTERM ? "SIGTERM" : sig == SIGHUP ? "SIGHUP" : "SIGINT";
    throw Interrupted(sig, std::string("interrupted by ") + name + ": " + what);
  }

 private:
  struct sigaction previous_int_ {};
  struct sigaction previous_term_ {};
  struct sigaction previous_hup_ {};
};

}  // namespace hf::apps
