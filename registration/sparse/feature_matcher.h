// Sparse visual features with depth, and their matching (Endres et al. 2012; Huang et al. 2011): ORB keypoints
// (OpenCV) on a frame's intensity, each with the 3-D point its depth gives, matched by Hamming distance with
// Lowe's ratio test and a cross-check. The `sparse` registration (registration/sparse.h) and anyone who needs
// appearance correspondences (relocalisation or loop closure against keyframes) use it:
//
//   hf::FeatureFrame kf = hf::extract_features(keyframe_pyramid.levels[0]);   // once per keyframe, keep it
//   hf::FeatureFrame cur = hf::extract_features(current_pyramid.levels[0]);
//   std::vector<hf::FeatureMatch> m = hf::match_features(cur, kf);
//   hf::RegistrationResult r = hf::align_feature_frames(cur, kf, hf::default_registration_options("sparse"));
//
// Frames: FeatureFrame points are in the camera frame of the level they came from (x right, y down, z forward,
// metres); pixels are in that level's pixel coordinates.
// Thread-safety: pure functions of their arguments (OpenCV may use its own threads inside).
// Failure modes: never throws for image content; a level without intensity, without valid depth or without texture
// gives an empty FeatureFrame (and no matches).
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "registration/frame_pyramid.h"

namespace hf {

// ORB detection and the depth a keypoint must have. The defaults are OpenCV's ORB defaults, with fewer scale levels
// (a 320x240 tracking image has little left at 1/1.2^7) and a smaller border, as RGB-D SLAM ran them on 640x480.
struct FeatureOptions {
  int max_features = 1000;     // keypoints kept (by FAST/Harris score, spread over the levels)
  int scale_levels = 4;        // ORB pyramid levels
  float scale_factor = 1.2f;   // ORB level-to-level scale
  int fast_threshold = 12;     // FAST intensity threshold (of 255, after the equalisation)
  // Global histogram equalisation of the 8-bit image before detection (cv::equalizeHist), so FAST's fixed threshold
  // sees the same contrast in dim and bright frames. On the `fast` preset (low-contrast checker walls) it turns
  // ~10 matches per pair (too few for RANSAC) into ~120, 58 % of them correct; on `room` it changes little.
  bool equalize_histogram = true;
  int patch_px = 19;           // ORB descriptor patch and border (OpenCV: 31 at 640x480)
  // A keypoint keeps its depth only where the four pixels around it are valid and within this many axial noise
  // sigmas (hf_kinect_axial_sigma_m) of each other: keypoints on depth edges mix foreground and background.
  float depth_edge_sigmas = 4.0f;
};

struct Feature {
  Eigen::Vector2f pixel;       // keypoint centre, level pixels (sub-pixel)
  Eigen::Vector3d point_m;     // its 3-D point in the camera frame (bilinear depth at the keypoint)
  int octave = 0;              // ORB level it was found on (its localisation sigma grows by scale_factor^octave)
  float scale = 1.0f;          // scale_factor^octave
  std::array<std::uint64_t, 4> descriptor{};  // 256-bit ORB descriptor
};

struct FeatureFrame {
  PinholeCamera camera;        // the level's camera
  std::vector<Feature> features;  // keypoints with a valid depth only
  bool empty() const { return features.empty(); }
};

// The features of one pyramid level (its intensity and vertices). Empty when the level has no intensity.
FeatureFrame extract_features(const FramePyramidLevel& level, const FeatureOptions& options = {});

struct MatchOptions {
  float ratio = 0.8f;          // Lowe's ratio test: best distance < ratio * second best (Lowe 2004: 0.8)
  bool cross_check = true;     // keep a match only when each feature is the other's best
  int max_distance_bits = 64;  // of 256: a best match further than this is no match (ORB: ~25% of the bits)
};

struct FeatureMatch {
  int current = 0;             // index into the current frame's features
  int reference = 0;           // index into the reference frame's features
  int distance_bits = 0;       // Hamming distance of the descriptors
};

// Matches every current feature to its nearest reference feature by Hamming distance, keeping those that pass the
// ratio test (and the cross-check), sorted by current index. Deterministic.
std::vector<FeatureMatch> match_features(const FeatureFrame& current, const FeatureFrame& reference,
                                         const MatchOptions& options = {});

// Hamming distance of two 256-bit descriptors.
int hamming_distance(const std::array<std::uint64_t, 4>& a, const std::array<std::uint64_t, 4>& b);

}  // namespace hf
