#include "core/timing.h"

namespace hf {

void StageTimes::add(const std::string& stage, double ms) {
  auto& s = stages_[stage];
  s.first += ms;
  s.second += 1;
}

double StageTimes::total_ms(const std::string& stage) const {
  auto it = stages_.find(stage);
  return it == stages_.end() ? 0.0 : it->second.first;
}

double StageTimes::mean_ms(const std::string& stage) const {
  auto it = stages_.find(stage);
  return (it == stages_.end() || it->second.second == 0) ? 0.0 : it->second.first / double(it->second.second);
}

long StageTimes::count(const std::string& stage) const {
  auto it = stages_.find(stage);
  return it == stages_.end() ? 0 : it->second.second;
}

}  // namespace hf
