// Shared by the pipeline tests: short synthetic sequences at half resolution, so each test takes seconds.
#pragma once

#include <functional>
#include <memory>
#include <string>

#include "core/camera.h"
#include "datasets/synthetic_source.h"
#include "io/frame_source.h"

namespace hf::slam::test {

inline datasets::SyntheticOptions half_res(const std::string& preset, int frames) {
  datasets::SyntheticOptions o;
  o.preset = preset;
  o.frames = frames;
  o.camera = PinholeCamera::preset("ros").scaled(1);  // 320x240
  return o;
}

// A frame source that hands frames of another through a modifier (for injecting garbage); frames for which
// `drop` says true are left out, as a frame missing from a dataset's list would be.
class ModifiedSource : public FrameSource {
 public:
  ModifiedSource(std::unique_ptr<FrameSource> inner, std::function<void(RgbdFrame&)> modify,
                 std::function<bool(const RgbdFrame&)> drop = nullptr)
      : inner_(std::move(inner)), modify_(std::move(modify)), drop_(std::move(drop)) {}
  FrameRead next() override {
    FrameRead r = inner_->next();
    while (r.status == FrameStatus::ok && drop_ && drop_(r.frame)) r = inner_->next();
    if (r.status == FrameStatus::ok) modify_(r.frame);
    return r;
  }
  const PinholeCamera& camera() const override { return inner_->camera(); }
  const std::string& camera_origin() const override { return inner_->camera_origin(); }
  size_t size() const override { return inner_->size(); }
  const std::string& name() const override { return inner_->name(); }
  const Trajectory& ground_truth() const override { return inner_->ground_truth(); }

 private:
  std::unique_ptr<FrameSource> inner_;
  std::function<void(RgbdFrame&)> modify_;
  std::function<bool(const RgbdFrame&)> drop_;
};

}  // namespace hf::slam::test
