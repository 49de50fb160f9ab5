#include "slam/reintegration.h"

#include <algorithm>
#include <cmath>
#include <utility>

#include <Eigen/Core>

#include "core/error.h"
#include "fusion/deintegrate.h"

namespace hf::slam {

void ReintegrationOptions::validate() const {
  if (!(min_translation_m >= 0) || !std::isfinite(min_translation_m))
    throw Error("reintegration.min_translation_m must be >= 0");
  if (!(min_rotation_deg >= 0) || !std::isfinite(min_rotation_deg))
    throw Error("reintegration.min_rotation_deg must be >= 0");
  if (!(min_displacement_vox >= 0) || !std::isfinite(min_displacement_vox))
    throw Error("reintegration.min_displacement_vox must be >= 0");
  if (!(budget_ms_per_frame >= 0) || !std::isfinite(budget_ms_per_frame))
    throw Error("reintegration.budget_ms_per_frame must be >= 0");
  if (frames_per_step < 0 || frames_per_step > 1000) throw Error("reintegration.frames_per_step must be in [0, 1000]");
  if (frames_after_loop < 0 || frames_after_loop > 100000)
    throw Error("reintegration.frames_after_loop must be in [0, 100000]");
  if (frames_after_loop_per_step < 1 || frames_after_loop_per_step > 100000)
    throw Error("reintegration.frames_after_loop_per_step must be in [1, 100000]");
  if (!(memory_budget_mb >= 0) || !std::isfinite(memory_budget_mb))
    throw Error("reintegration.memory_budget_mb must be >= 0");
}

FusedFrames::FusedFrames(const ReintegrationOptions& options) : options_(options) { options_.validate(); }

double correction_displacement_m(const SE3& T_old_new, const PinholeCamera& camera, double range_m) {
  const Eigen::Matrix3d R = T_old_new.rotation();
  const Eigen::Vector3d t = T_old_new.translation();
  double worst = t.norm();  // the camera centre
  const double z = std::max(range_m, 0.0);
  for (const double u : {-0.5, double(camera.width) - 0.5})
    for (const double v : {-0.5, double(camera.height) - 0.5}) {
      const Eigen::Vector3d p(z * (u - camera.cx) / camera.fx, z * (v - camera.cy) / camera.fy, z);
      worst = std::max(worst, (R * p + t - p).norm());
    }
  return worst;
}

void FusedFrames::add(size_t frame_index, size_t keyframe, const SE3& T_world_keyframe, const SE3& T_world_frame,
                      CompressedRgbd images, double max_depth_m) {
  Frame f;
  f.frame_index = frame_index;
  f.keyframe = keyframe;
  f.max_depth_m = std::isfinite(max_depth_m) ? std::max(max_depth_m, 0.0) : 8.0;
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

void FusedFrames::schedule(const KeyframeMap& keyframes, const PinholeCamera& camera, double voxel_m) {
  std::vector<std::pair<double, size_t>> moved;  // (displacement, index)
  const bool legacy = options_.min_translation_m > 0 || options_.min_rotation_deg > 0;
  for (size_t i = 0; i < frames_.size(); ++i) {
    const Frame& f = frames_[i];
    if (f.images.empty() || f.keyframe >= keyframes.size()) continue;
    const SE3 d = f.T_world_fused.inverse() * anchored_pose(f, keyframes);
    const double moved_m = correction_displacement_m(d, camera, f.max_depth_m);
    if (!(moved_m > options_.min_displacement_vox * voxel_m)) continue;
    if (legacy && d.translation().norm() <= options_.min_translation_m &&
        d.angle_rad() * 180.0 / M_PI <= options_.min_rotation_deg)
      continue;
    moved.emplace_back(moved_m, i);
  }
  // Ascending, ties by index: the most-displaced ends at the back and is taken first, the order fixed by the input.
  std::sort(moved.begin(), moved.end());
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
