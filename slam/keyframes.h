// Keyframes: the frames the pipeline keeps to relocalise against and to close loops with.
//
//   KeyframeMap map(options);
//   if (map.wants_keyframe(T_world_camera)) map.add(frame_index, t, T_world_camera, information, depth, colour);
//   DepthImage d = map.depth(id); ColorImage c = map.colour(id);   // decoded on demand
//
// Selection (DVO-SLAM / ElasticFusion style, by motion): a tracked frame becomes a keyframe when the camera moved
// more than min_translation_m or turned more than min_rotation_deg since the last keyframe, or when
// max_frames_between frames have passed. Each keyframe stores its pose, its registration information matrix
// (xi = (omega, v) order), and its depth and colour compressed in memory: depth as a 16-bit PNG in units of
// 1/5000 m (TUM's unit: lossless for TUM and 7-Scenes depth), colour as a JPEG. When the stored images exceed
// memory_budget_mb the oldest keyframes' images are dropped (the keyframe keeps its pose and appearance code, but
// can no longer be registered against): `has_images(id)` says which.
//
// Thread-safety: none; the pipeline owns one.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <vector>

#include "core/image.h"
#include "core/se3.h"

namespace hf::slam {

struct KeyframeOptions {
  // Motion since the last keyframe that makes a new one. 0.1 m / 10 deg give ~1 keyframe per 10-30 frames on
  // hand-held TUM fr1 (chosen on tum_fr1_rpy_first150; bench/results/tracking.md).
  double min_translation_m = 0.1;
  double min_rotation_deg = 10.0;
  int max_frames_between = 60;     // a keyframe at least this often while tracking (a still camera)
  double memory_budget_mb = 512.0;  // compressed images of all keyframes together
  int jpeg_quality = 90;

  void validate() const;  // hf::Error naming the bad field
};

// One RGB-D frame compressed in memory: depth as a 16-bit PNG in 1/5000 m units, colour as a JPEG (lossy; empty
// when the frame had none). What keyframes and the re-integration store (slam/reintegration.h) keep.
struct CompressedRgbd {
  std::vector<std::uint8_t> depth_png, colour_jpg;

  static CompressedRgbd encode(const DepthImage& depth, const ColorImage& colour, int jpeg_quality);
  DepthImage depth() const;   // hf::Error for corrupt data; empty image when none is stored
  ColorImage colour() const;  // likewise
  size_t bytes() const { return depth_png.size() + colour_jpg.size(); }
  bool empty() const { return depth_png.empty(); }
  void clear();
};

struct Keyframe {
  size_t id = 0;            // index in the map, in order of creation
  size_t frame_index = 0;   // the frame it was made from
  double timestamp_s = 0.0;
  SE3 T_world_camera;       // its pose (corrected by loop closure)
  // Its pose relative to the previous keyframe as tracked (identity for the first): the odometry measurement the
  // pose graph keeps while loop closures move both ends.
  SE3 T_previous_this;
  double path_m = 0.0;      // camera path length from the first keyframe, summed over keyframe steps
  Matrix6d information = Matrix6d::Zero();  // of the registration that placed it (zero for the first)
  // The odometry edge measured independently of the map: this keyframe registered against the previous one's own
  // images (set_odometry). Zero information when it was not measured; the pose graph then keeps T_previous_this.
  // Why both: tracking against the global model snaps back onto old walls as they come into view, and that
  // correction lands in T_previous_this, where a loop edge can no longer see the drift it removed from the end of
  // the chain but not from its middle. The keyframe-to-keyframe measurement keeps the drift in the chain, so the
  // loop edge spreads its correction over every keyframe of the loop.
  SE3 T_previous_this_registered;
  Matrix6d odometry_information = Matrix6d::Zero();
  CompressedRgbd images;    // empty once dropped for the budget
};

class KeyframeMap {
 public:
  explicit KeyframeMap(const KeyframeOptions& options = {});

  // True when a frame at T_world_camera (frame index `frame_index`) should become a keyframe.
  bool wants_keyframe(const SE3& T_world_camera, size_t frame_index) const;
  // Stores a keyframe; colour may be empty. Returns its id.
  size_t add(size_t frame_index, double timestamp_s, const SE3& T_world_camera, const Matrix6d& information,
             const DepthImage& depth, const ColorImage& colour);
  // The same with the images already compressed (options' jpeg_quality is then the caller's business).
  size_t add(size_t frame_index, double timestamp_s, const SE3& T_world_camera, const Matrix6d& information,
             CompressedRgbd images);

  size_t size() const { return keyframes_.size(); }
  bool empty() const { return keyframes_.empty(); }
  const Keyframe& operator[](size_t id) const { return keyframes_.at(id); }
  void set_pose(size_t id, const SE3& T_world_camera) { keyframes_.at(id).T_world_camera = T_world_camera; }
  // Gives keyframe id its images (one added with empty images while they were being compressed).
  void set_images(size_t id, CompressedRgbd images);
  // Records keyframe id's pose relative to keyframe id - 1 as registered between their own images.
  void set_odometry(size_t id, const SE3& T_previous_this, const Matrix6d& information) {
    Keyframe& k = keyframes_.at(id);
    k.T_previous_this_registered = T_previous_this;
    k.odometry_information = information;
  }
  const std::vector<Keyframe>& all() const { return keyframes_; }

  bool has_images(size_t id) const { return !keyframes_.at(id).images.empty(); }
  // Decoded images (metres; 0 = no depth). Empty images when has_images(id) is false.
  DepthImage depth(size_t id) const;
  ColorImage colour(size_t id) const;
  size_t memory_bytes() const { return bytes_; }

 private:
  KeyframeOptions options_;
  std::vector<Keyframe> keyframes_;
  size_t bytes_ = 0;
  size_t dropped_ = 0;  // keyframes [0, dropped_) have no images
};

// Depth (metres) quantised to the 1/5000 m unit keyframes store, so what is integrated and what a keyframe
// stores are the same numbers (NaN / out of range -> 0).
void quantise_depth_tum(DepthImage* depth);

}  // namespace hf::slam
