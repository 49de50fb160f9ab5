// PCL's GICP and NDT (bench/pcl_reference.h) and, where Open3D is installed, Open3D's point-to-plane ICP, coloured
// ICP and hybrid RGB-D odometry (bench/open3d_reference.h) as peer rows of the benchmark: frame-to-frame odometry
// through their APIs, judged by the same ATE/RPE as hashfusion's runs.
//
// Per frame: read it, back-project every `pixel_stride`-th pixel of the depth with the source's camera
// (preprocess; Open3D's peers build their own clouds or pyramids from the frame's images inside track), align it to
// the last good frame starting from the constant-velocity guess (identity right
// after a lost frame or with constant_velocity off), and chain T_world_cur = T_world_prev * T_prev_cur (track).
// A frame is LOST (pose_valid false, not used as the next target) when the library does not converge (Open3D ICP:
// no correspondence; its odometry: its failure flag), throws, gets fewer
// than `min_points` points, or implies a motion faster than the speed limits since the last good frame, the same
// policy as slam::Pipeline. The first frame is placed at its ground-truth pose when it has one, else at the identity.
// There is no map: integrate and raycast do not exist for peers.
//
// Thread-safety: one call per source (PCL's GICP/NDT are single-threaded here; Open3D may use OpenMP inside).
#pragma once

#include <Eigen/Core>
#include <atomic>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "io/frame_source.h"
#include "io/trajectory_io.h"

namespace hf::bench {

// The peers built in: "gicp", "ndt" with PCL, "o3d-icp", "o3d-colored-icp", "o3d-rgbd" with Open3D; empty
// without either.
std::vector<std::string> peer_names();

struct PeerOptions {
  float voxel_m = 0.04f;            // voxel-grid downsampling of both clouds (bench_registration's setting)
  float ndt_resolution_m = 0.2f;    // NDT cell size
  int pixel_stride = 2;             // back-project every k-th pixel in x and y
  bool constant_velocity = true;    // initial guess: the last inter-frame motion (else the identity)
  double max_speed_m_per_s = 6.0;   // as slam::PipelineConfig
  double max_angular_speed_deg_per_s = 720.0;
  int min_points = 100;             // fewer back-projected points: lost without calling PCL
  // Throws hf::Error naming the bad field.
  void validate() const;
};

struct PeerFrame {
  size_t index = 0;
  double timestamp_s = 0.0;
  SE3 T_world_camera;        // while lost: the last good pose
  bool pose_valid = false;
  double ms_read = 0.0, ms_preprocess = 0.0, ms_track = 0.0;
  std::string message;       // why the frame was lost, empty otherwise
};

struct PeerRun {
  std::vector<PeerFrame> frames;  // decoded frames, in order
  long frames_bad = 0;            // unreadable frames, skipped
  bool interrupted = false;
  long frames_lost() const;
  Trajectory estimate() const;    // the valid poses
};

// Camera-frame points of the valid depth pixels (every stride-th pixel in x and y).
std::vector<Eigen::Vector3f> backproject_depth(const DepthImage& depth, const PinholeCamera& camera, int stride);

// Runs peer `method` (one of peer_names()) over `source`: at most max_frames frames read (0 = all), stopping early when
// *stop becomes true, with a progress bar when progress_label is non-empty. Throws hf::Error for an unknown method,
// bad options, or a peer whose library (PCL, Open3D) this build lacks.
PeerRun run_peer(FrameSource& source, const std::string& method, const PeerOptions& options, long max_frames = 0,
                 const std::atomic<bool>* stop = nullptr, const std::string& progress_label = "");

}  // namespace hf::bench
