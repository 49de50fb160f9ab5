#include "datasets/synthetic_source.h"

#include <cstring>
#include <optional>

#include "core/error.h"

namespace hf::datasets {
namespace {

class SyntheticSource : public FrameSource {
 public:
  explicit SyntheticSource(const SyntheticOptions& options)
      : sequence_(options),
        name_("synthetic '" + options.preset + "' (seed " + std::to_string(options.seed) + ", " +
              std::to_string(options.frames) + " frames" + (options.noise_enabled ? "" : ", no noise") + ")"),
        origin_("synthetic camera " + options.camera.describe()) {
    for (int i = 0; i < sequence_.size(); ++i)
      ground_truth_.push_back({sequence_.timestamp_s(i), sequence_.T_world_camera(i)});
  }

  FrameRead next() override {
    if (next_ >= sequence_.size()) return FrameRead{};  // end
    return render(next_++);
  }
  // Frame i depends only on (options, i) (datasets/synthetic_sequence.h), so out of order is the same frame.
  std::optional<FrameRead> read_at(size_t index) const override {
    if (index >= size_t(sequence_.size())) return std::nullopt;
    return render(int(index));
  }
  const PinholeCamera& camera() const override { return sequence_.camera(); }
  const std::string& camera_origin() const override { return origin_; }
  size_t size() const override { return size_t(sequence_.size()); }
  const std::string& name() const override { return name_; }
  const Trajectory& ground_truth() const override { return ground_truth_; }

 private:
  FrameRead render(int i) const {
    FrameRead r;
    SyntheticFrame f = sequence_.frame(i);
    r.status = FrameStatus::ok;
    r.frame.index = size_t(i);
    r.frame.timestamp_s = f.timestamp_s;
    r.frame.depth = std::move(f.depth);
    r.frame.color = std::move(f.color);
    r.frame.T_world_camera_gt = f.T_world_camera;
    r.frame.depth_file = name_ + " depth " + std::to_string(i);
    r.frame.color_file = name_ + " colour " + std::to_string(i);
    return r;
  }

  SyntheticSequence sequence_;
  std::string name_, origin_;
  Trajectory ground_truth_;
  int next_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> open_synthetic(const std::string& preset, SyntheticOptions options) {
  options.preset = preset;
  return std::make_unique<SyntheticSource>(options);
}

bool is_synthetic_input(const std::string& input) {
  return input.rfind(kSyntheticPrefix, 0) == 0;
}

std::unique_ptr<FrameSource> open_synthetic_input(const std::string& input, SyntheticOptions options) {
  if (!is_synthetic_input(input))
    throw Error("expected a synthetic input 'synthetic:PRESET', got '" + input + "'");
  return open_synthetic(input.substr(std::strlen(kSyntheticPrefix)), options);
}

}  // namespace hf::datasets
