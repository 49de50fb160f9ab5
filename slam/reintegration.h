// A map that follows the corrected poses (BundleFusion, Dai et al. 2017): every frame fused into the TSDF is kept
// (compressed, slam/keyframes.h CompressedRgbd) with the pose it was fused at and its anchor, the keyframe it was
// tracked from. When loop closure moves keyframes, each frame's pose moves with its anchor
// (T_world_frame = T_world_keyframe * T_keyframe_frame); the frames that moved by more than min_translation_m or
// min_rotation_deg are re-fused (fusion::reintegrate: deintegrate at the old pose, integrate at the new one),
// most-changed first: frames_after_loop of them at once after a closure, then frames_per_step per processed
// frame so that tracking never stalls.
//
//   FusedFrames fused(options);
//   fused.add(index, keyframe, T_world_keyframe, T_world_frame, images);   // after each integrate()
//   fused.schedule(keyframes);                                  // after a loop closure moved keyframes
//   fused.step(options.frames_per_step, grid, camera, params, &store);           // once per processed frame
//   fused.refuse_all(keyframes, grid, camera, params, &store);  // --global: the whole map from the final poses
//
// Memory: beyond memory_budget_mb the oldest frames' images are dropped; such a frame stays fused at its old pose
// (counted in dropped()). Re-fusion is exact up to the TSDF's quantisation while no voxel reached the weight cap
// (fusion/deintegrate.h states what holds beyond it).
// Thread-safety: none; the pipeline owns one.
#pragma once

#include <cstddef>
#include <vector>

#include "core/camera.h"
#include "core/se3.h"
#include "fusion/integrate.h"
#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"
#include "slam/keyframes.h"

namespace hf::slam {

struct ReintegrationOptions {
  bool enabled = true;
  double min_translation_m = 0.005;  // a frame moved by more than this (or the rotation) is re-fused
  double min_rotation_deg = 0.5;
  int frames_per_step = 2;           // re-fusions per processed frame (~10 ms each at 640x480 on 2 cores)
  // Re-fusions right after a loop closure moved the keyframes, before the next frame is tracked. The most-changed
  // frames are the ones just before the loop, whose surfaces the camera sees now: until they are re-fused, the
  // next frames track against them at their old poses and snap back by the correction. 16 on the synthetic lap
  // (640x480): ATE 2.54 -> 1.9 mm, the loop frame ~130 ms longer (bench/results/tracking.md).
  int frames_after_loop = 16;
  double memory_budget_mb = 2048.0;  // compressed images of every fused frame (keyframes.jpeg_quality for colour)

  void validate() const;  // hf::Error naming the bad field
};

class FusedFrames {
 public:
  explicit FusedFrames(const ReintegrationOptions& options = {});

  // `images` as the frame was fused (the pipeline compresses each frame once, for this store and the keyframes).
  void add(size_t frame_index, size_t keyframe, const SE3& T_world_keyframe, const SE3& T_world_frame,
           CompressedRgbd images);
  // Queues the frames whose anchored pose moved past the thresholds since they were fused, most-changed first.
  void schedule(const KeyframeMap& keyframes);
  // Re-fuses up to n queued frames at their anchored poses; returns how many were re-fused.
  size_t step(size_t n, const KeyframeMap& keyframes, fusion::VoxelBlockGrid& grid, const PinholeCamera& camera,
              const fusion::IntegrateParams& params, fusion::BlockStore* store);
  // Clears the map and fuses every stored frame at its anchored pose (frames without images are lost to it).
  void refuse_all(const KeyframeMap& keyframes, fusion::VoxelBlockGrid& grid, const PinholeCamera& camera,
                  const fusion::IntegrateParams& params, fusion::BlockStore* store);

  size_t size() const { return frames_.size(); }
  size_t pending() const { return queue_.size(); }
  size_t refused() const { return refused_; }  // re-fusions done so far
  size_t dropped() const { return dropped_; }
  size_t memory_bytes() const { return bytes_; }

 private:
  struct Frame {
    size_t frame_index = 0, keyframe = 0;
    SE3 T_keyframe_frame, T_world_fused;
    CompressedRgbd images;
  };
  SE3 anchored_pose(const Frame& f, const KeyframeMap& keyframes) const;

  ReintegrationOptions options_;
  std::vector<Frame> frames_;
  std::vector<size_t> queue_;  // indices into frames_, next first at the back
  size_t bytes_ = 0, dropped_ = 0, refused_ = 0;
};

}  // namespace hf::slam
