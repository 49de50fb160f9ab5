// Per-stage wall-clock timing for the pipeline and the benchmark.
//
//   StageTimes times;
//   { ScopedTimer t(times, "track"); ... }   // adds the elapsed milliseconds to "track"
//   times.mean_ms("track");
//
// StageTimes is not thread-safe: one per thread or per pipeline.
#pragma once

#include <chrono>
#include <map>
#include <string>

namespace hf {

// Wall-clock milliseconds since t0 on the steady clock (for stage timings: monotonic, never negative).
inline double ms_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
}

class StageTimes {
 public:
  void add(const std::string& stage, double ms);
  double total_ms(const std::string& stage) const;
  double mean_ms(const std::string& stage) const;  // 0 when the stage never ran
  long count(const std::string& stage) const;
  const std::map<std::string, std::pair<double, long>>& stages() const { return stages_; }

 private:
  std::map<std::string, std::pair<double, long>> stages_;  // stage -> (sum ms, count)
};

class ScopedTimer {
 public:
  ScopedTimer(StageTimes& times, std::string stage)
      : times_(&times), stage_(std::move(stage)), start_(std::chrono::steady_clock::now()) {}
  ScopedTimer(const ScopedTimer&) = delete;
  ScopedTimer& operator=(const ScopedTimer&) = delete;
  ~ScopedTimer() { times_->add(stage_, elapsed_ms()); }
  double elapsed_ms() const {
    return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start_).count();
  }

 private:
  StageTimes* times_;
  std::string stage_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace hf
