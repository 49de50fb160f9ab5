#include "slam/reintegration.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include "core/error.h"
#include "fusion/deintegrate.h"

namespace hf::slam {

void ReintegrationOptions::validate() const {
  if (!(min_translation_m >= 0) || !std::isfinite(min_translation_m))
    throw Error("reintegration.min_translation_m must be >= 0");
  if (!(min_rotation_deg >= 0) || !std::isfinite(min_rotation_deg))
    throw Error("reintegration.min_rotation_deg must be >= 0");
  if (frames_per_step < 0 || frames_per_step > 1000) throw Error("reintegration.frames_per_step must be in [0, 1000]");
  if (frames_after_loop < 0 || frames_after_loop > 100000)
    throw Error("reintegration.frames_after_loop must be in [0, 100000]");
  if (!(memory_budget_mb >= 0) || !std::isfinite(memory_budget_mb))
    throw Error("reintegration.memory_budget_mb must be >= 0");
}

FusedFrames::FusedFrames(const ReintegrationOptions& options) : options_(options) { options_.validate(); }

void FusedFrames::add(size_t frame_index, size_t keyframe, const SE3& T_world_keyframe, const SE3& T_world_frame,
                      CompressedRgbd images) {
  Frame f;
  f.frame_index = frame_index;
  f.keyframe = keyframe;
  f.T_keyframe_frame = T_world_keyframe.inverse() * T_world_frame;
  f.T_world_fused = T_world_frame;
  f.images = std::move(images);
  bytes_ += f.images.bytes();
  frames_.push_back(std::move(f));
  const double budget = options_.memory_budget_mb * 1024.0 * 1024.0;
  while (double(bytes_) > budget && dropped_ < frames_.size()) {
    bytes_ -= frames_[dropped_].images.bytes();
    frames_[dropped_++].images.clear();
  }
}

SE3 FusedFrames::anchored_pose(const Frame& f, const KeyframeMap& keyframes) const {
  return keyframes[f.keyframe].T_world_camera * f.T_keyframe_frame;
}

void FusedFrames::schedule(const KeyframeMap& keyframes) {
  std::vector<std::pair<double, size_t>> moved;  // (change, index)
  for (size_t i = 0; i < frames_.size(); ++i) {
    const Frame& f = frames_[i];
    if (f.images.empty() || f.keyframe >= keyframes.size()) continue;
    const SE3 d = f.T_world_fused.inverse() * anchored_pose(f, keyframes);
    const double t_m = d.translation().norm();
    const double r_deg = d.angle_rad() * 180.0 / M_PI;
    if (t_m <= options_.min_translation_m && r_deg <= options_.min_rotation_deg) continue;
    // One scale for both: a degree moves a point 2 m away by ~3.5 cm.
    moved.emplace_back(t_m + 0.035 * r_deg, i);
  }
  std::sort(moved.begin(), moved.end());  // ascending: the most-changed ends at the back, taken first
  queue_.clear();
  for (const auto& m : moved) queue_.push_back(m.second);
}

size_t FusedFrames::step(size_t n, const KeyframeMap& keyframes, fusion::VoxelBlockGrid& grid,
                         const PinholeCamera& camera, const fusion::IntegrateParams& params,
                         fusion::BlockStore* store) {
  size_t done = 0;
  while (done < n && !queue_.empty()) {
    Frame& f = frames_[queue_.back()];
    queue_.pop_back();
    if (f.images.empty()) continue;
    const SE3 T_new = anchored_pose(f, keyframes);
    fusion::reintegrate(grid, f.images.depth(), f.images.colour(), camera, f.T_world_fused, T_new, params, store);
    f.T_world_fused = T_new;
    ++done;
    ++refused_;
  }
  return done;
}

void FusedFrames::refuse_all(const KeyframeMap& keyframes, fusion::VoxelBlockGrid& grid, const PinholeCamera& camera,
                             const fusion::IntegrateParams& params, fusion::BlockStore* store) {
  grid.clear();
  if (store) store->clear();
  queue_.clear();
  for (Frame& f : frames_) {
    if (f.images.empty()) continue;
    f.T_world_fused = anchored_pose(f, keyframes);
    fusion::integrate(grid, f.images.depth(), f.images.colour(), camera, f.T_world_fused, params, store);
    ++refused_;
  }
}

}  // namespace hf::slam
