// A map that follows the corrected poses (BundleFusion, Dai et al. 2017): every frame fused into the TSDF is kept
// (compressed, slam/keyframes.h CompressedRgbd) with the pose it was fused at and its anchor, the keyframe it was
// tracked from. When loop closure moves keyframes, each frame's pose moves with its anchor
// (T_world_frame = T_world_keyframe * T_keyframe_frame). Re-fusion is in proportion to what changed: a frame is
// re-fused (fusion::reintegrate: deintegrate at the old pose, integrate at the new one) only when its correction
// moves some voxel it fused by more than min_displacement_vox voxels (correction_displacement_m: the exact
// largest displacement over the frame's view frustum out to the farthest depth it integrated), most-displaced
// first: frames_after_loop of them at once after a closure, then frames_per_step per processed frame (offline) or
// as many as fit budget_ms_per_frame (realtime), so that tracking never stalls.
//
//   FusedFrames fused(options);
//   fused.add(index, keyframe, T_world_keyframe, T_world_frame, images, max_depth_m);  // after each integrate()
//   fused.schedule(keyframes, camera, voxel_m);                 // after a loop closure moved keyframes
//   fused.step(options.frames_per_step, grid, camera, params, &store);           // once per processed frame
//   fused.refuse_all(keyframes, grid, camera, params, &store);  // --global: the whole map from the final poses
//
// The same correction is never applied twice: a frame remembers the pose it is fused at, and schedule() compares
// the anchored pose with that, so a re-fused frame only comes back when its anchor moves again. The backlog
// (pending()) never exceeds the frames stored with images (bounded by memory_budget_mb), each schedule() replaces
// it (never adds to it), and the pipeline's finish() drains it to 0.
//
// Memory: beyond memory_budget_mb the oldest frames' images are dropped; such a frame stays fused at its old pose
// (counted in dropped()). Re-fusion is exact up to the TSDF's quantisation while no voxel reached the weight cap
// (fusion/deintegrate.h states what holds beyond it).
// Thread-safety: none; the pipeline owns one and uses it on its tracking thread, between frames.
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
  // A frame is re-fused when its correction moves some voxel of its view by more than this many voxels: below
  // half a voxel the re-fused TSDF would differ from the fused one by less than its own quantisation of the surface.
  double min_displacement_vox = 0.5;
  // Further, optional, thresholds (0 = off): the correction's translation or rotation must also exceed one of them.
  double min_translation_m = 0.0;
  double min_rotation_deg = 0.0;
  int frames_per_step = 2;           // re-fusions per processed frame, offline (~10 ms each at 640x480 on 2 cores)
  // Realtime mode (Pipeline::set_realtime): re-fusions continue between two frames while less than this has been
  // spent on them (so one re-fusion can overrun it by its own length, ~10 ms); frames_per_step is then unused.
  double budget_ms_per_frame = 10.0;
  // Re-fusions owed after a loop closure moved the keyframes (offline), on top of frames_per_step. The most-changed
  // frames are the ones just before the loop, whose surfaces the camera sees now: until they are re-fused, the
  // next frames track against them at their old poses and snap back by the correction. 16 on the synthetic lap
  // (640x480): ATE 2.54 -> 1.9 mm (bench/results/tracking.md). They are paid at most frames_after_loop_per_step
  // per frame, starting on the frame that applies the loop. All at once (16, the default) costs the loop frame
  // ~160 ms at 640x480, the session's worst frame; spread, the lap's ATE grows (1.40 mm at 16, 1.46 at 8, 1.50 at
  // 4; bench/results/backend.md), so the default keeps the accuracy and the spreading is the latency user's choice.
  int frames_after_loop = 16;
  int frames_after_loop_per_step = 16;
  // Compressed images of the fused frames (keyframes.jpeg_quality for colour); beyond it the oldest are dropped
  // (they stay fused at their last pose). 512 MiB holds ~1400 640x480 frames of the synthetic loop (~370 KiB
  // each; real TUM / 7-Scenes frames compress smaller): on its 3000-frame session the same ATE and re-fusions as
  // 2048 (after the first lap corrections move old frames by less than half a voxel), peak RSS 1376 -> 1123 MiB
  // (bench/results/backend.md).
  double memory_budget_mb = 512.0;

  void validate() const;  // hf::Error naming the bad field
};

// The largest distance a point seen by `camera` out to depth range_m moves when its frame's pose changes by
// T_old_new (= T_world_old^-1 * T_world_new): |T_old_new p - p| is convex in p, so its maximum over the view
// frustum (a pyramid: the camera centre and the image corners at range_m) lies at one of those five points.
double correction_displacement_m(const SE3& T_old_new, const PinholeCamera& camera, double range_m);

class FusedFrames {
 public:
  explicit FusedFrames(const ReintegrationOptions& options = {});

  // `images` as the frame was fused (the pipeline compresses each frame once, for this store and the keyframes).
  // max_depth_m: the farthest depth the frame integrated (bounds how far its correction can move a voxel).
  void add(size_t frame_index, size_t keyframe, const SE3& T_world_keyframe, const SE3& T_world_frame,
           CompressedRgbd images, double max_depth_m = 8.0);
  // Queues the frames whose anchored pose moved past the thresholds since they were fused, most-displaced first,
  // replacing the queue. `camera` is the frames' camera, voxel_m the map's voxel size.
  void schedule(const KeyframeMap& keyframes, const PinholeCamera& camera, double voxel_m);
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
    double max_depth_m = 8.0;
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
