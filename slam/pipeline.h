// The dense RGB-D SLAM pipeline: one frame in, one tracked pose and an updated map out (KinectFusion's loop over
// the voxel-hashed TSDF, with the registration method chosen by name).
//
//   hf::slam::Pipeline p(config, camera);
//   for (each frame) { hf::slam::FrameResult r = p.process(frame); ... }
//   hf::TriangleMesh mesh = p.extract_mesh();
//
// Stages of process(), each timed into FrameResult::ms (the caller times `read`):
//   preprocess  frame pyramid of the new frame: bilateral-filtered depth, vertices, normals, intensity, gradients.
//   track       align the frame to the reference: the model raycast at the last good pose for the geometric rows
//               (frame-to-model, KinectFusion) and the previous frame's intensity for the photometric rows
//               (frame-to-frame: the report, section 3.2, finds the model colour too blurred to track against).
//               Both live in the camera frame of the last good pose, so T_world_cur = T_world_ref * T_ref_cur.
//   decide      the failure policy below.
//   integrate   fuse the frame into the TSDF at its pose (only when the frame was accepted).
//   raycast     the model maps at the new pose: the next frame's reference.
//
// Failure policy (it lives here, not in registration): a frame whose registration is not usable, is degenerate in
// more than `max_degenerate_dims` directions, or implies a motion faster than max_speed_m_per_s /
// max_angular_speed_deg_per_s since the last good frame is LOST: it is not integrated, the pose stays at the last
// good one (so the reference - raycast and intensity of the last good frame - is left untouched), and the next frame
// is tracked against that same reference from the last good pose with no motion prior, coarse level first (which
// is how the driver always starts). When it succeeds again the frame is RECOVERED. A bad frame never touches the
// map. While lost, FrameResult::T_world_camera holds the last good pose and `pose_valid` is false, so a trajectory
// written by the caller can leave lost frames out.
//
// The first frame (or the first after the map was empty) is placed at its ground-truth pose when the dataset has
// one, else at the identity, and integrated without tracking: the map then lives in the ground-truth world frame,
// which makes meshes directly comparable with the scene (ATE aligns trajectories anyway).
//
// `registration = "groundtruth"` skips tracking and uses each frame's ground-truth pose (fusion-only runs);
// frames without ground truth are then lost.
//
// Thread-safety: one process() at a time; it uses all cores itself.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/se3.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"
#include "io/frame_source.h"
#include "io/mesh.h"
#include "registration/frame_pyramid.h"
#include "registration/registration.h"
#include "slam/pipeline_config.h"

namespace hf::slam {

enum class TrackState {
  initialised,  // first frame: placed (ground truth or identity) and integrated
  tracked,      // registration accepted
  recovered,    // accepted after one or more lost frames
  lost,         // rejected by the failure policy: not integrated, pose = last good pose
  groundtruth,  // pose from the dataset (registration = groundtruth)
};
const char* to_string(TrackState state);

// Milliseconds per stage for one frame (0 for stages that did not run).
struct StageMs {
  double read = 0, preprocess = 0, track = 0, integrate = 0, raycast = 0;
  double total() const { return read + preprocess + track + integrate + raycast; }
};

struct FrameResult {
  size_t index = 0;
  double timestamp_s = 0.0;
  TrackState state = TrackState::lost;
  SE3 T_world_camera;        // the estimate; while lost, the last good pose
  bool pose_valid = false;   // false while lost (and for groundtruth frames without ground truth)
  bool integrated = false;
  std::optional<RegistrationResult> registration;  // when tracking ran
  std::string message;       // why the frame was lost (one line), empty otherwise
  StageMs ms;                // `read` is left for the caller
};

class Pipeline {
 public:
  // Validates the config; throws hf::Error for a bad config, an unknown registration or an unavailable backend.
  Pipeline(const PipelineConfig& config, const PinholeCamera& camera);
  ~Pipeline();
  Pipeline(const Pipeline&) = delete;
  Pipeline& operator=(const Pipeline&) = delete;

  // Processes one decoded frame (depth and colour of the camera's size). Never throws for bad pixel values;
  // throws hf::Error for a frame of the wrong size and fusion::CapacityError when the block pool is exhausted.
  FrameResult process(const RgbdFrame& frame);

  const PipelineConfig& config() const { return config_; }
  const PinholeCamera& camera() const { return camera_; }
  const fusion::VoxelBlockGrid& map() const { return grid_; }
  const fusion::BlockStore& store() const { return store_; }
  size_t frames_processed() const { return frames_; }
  size_t frames_lost() const { return lost_; }
  std::optional<SE3> last_good_pose() const { return last_good_; }

  // The whole map (resident and streamed-out blocks) as a welded, coloured mesh.
  TriangleMesh extract_mesh() const;
  // A shaded raycast of the model from `T_world_camera` with the pipeline's camera, for people.
  ColorImage render(const SE3& T_world_camera) const;

 private:
  struct Reference;
  PipelineConfig config_;
  PinholeCamera camera_;
  PinholeCamera tracking_camera_;  // camera_.scaled(tracking_level)
  fusion::VoxelBlockGrid grid_;
  fusion::BlockStore store_;
  std::unique_ptr<Registration> registration_;  // null for groundtruth
  std::unique_ptr<Reference> reference_;        // model maps + intensity at the last good pose
  std::optional<SE3> last_good_;
  double last_good_time_s_ = 0.0;
  SE3 velocity_;          // T_prev_cur of the last accepted frame pair
  bool was_lost_ = false;
  size_t frames_ = 0, lost_ = 0;
};

}  // namespace hf::slam
