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

namespace hf::slam {

struct PipelineConfig {
  std::string registration = "combined";  // a registry name (make_registration) or "groundtruth"
  std::string backend = "cpu";             // reduction backend: cpu | opencl
  fusion::VolumeParams volume;             // voxel_m 0.01, truncation 4 voxels, capacity, weight cap
  fusion::IntegrateParams integrate;
  // The tracking raycast. No shading and no colour: tracking reads neither (photometric rows are frame to frame;
  // render() turns shading on for its own raycast). The crossing is refined to 0.05 voxel, not to raycast's
  // default 0.001 (which exists so hinted and full marches agree exactly): on fr1/rpy the ATE is the same to 1 um
  // and the raycast ~10-15 % cheaper (bench/results/pipeline.md).
  fusion::RaycastOptions raycast{.refine_tol_vox = 0.05, .shade = false, .color = false};
  // Where the frame has no depth, hint the tracking raycast with the last model raycast moved to the new pose
  // (fusion::forward_project_depth) instead of marching those rays from the near end of their tile.
  bool model_hint = true;
  FramePyramidOptions pyramid;
  // The pyramid level tracking starts at: 0 = full resolution; 1 = half (DVO-SLAM tracked at 320x240 in real time
  // on one core). Tracking then uses pyramid.levels levels from there, and the model is raycast at that resolution;
  // integration always uses the full-resolution frame. Default 1, measured on TUM fr1/rpy (150 frames, combined):
  // ATE 1.87 cm at 2.9 fps from level 1 against 2.29 cm at 1.0 fps from level 0 (bench/results/pipeline.md): the
  // full-resolution level adds cost, and with motion blur and rolling shutter no accuracy.
  int tracking_level = 1;
  // Registration options; unset = the method's defaults (default_registration_options) with rgb_weight below.
  std::optional<RegistrationOptions> registration_options;
  // lambda of eq. 48 when registration_options is unset, measured in this pipeline (frame-to-model ICP rows,
  // frame-to-frame photometric rows) on TUM fr1/rpy, 150 frames, 320x240 tracking: ATE 3.06 cm at 0.1, 1.87 cm at
  // 0.4, 2.14 cm at 1.0 (bench/results/pipeline.md). The registration's own default (0.1) is the optimum of the
  // frame-to-frame sweep, where the ICP reference is as sharp as the frame; the fused model's smoother geometry
  // shifts the balance towards the photometric rows.
  float rgb_weight = 0.4f;
  // Motion prior: the initial guess of T_ref_cur is the last inter-frame motion (constant velocity) when true, the
  // identity (KinectFusion) when false. Never used right after a lost frame.
  bool constant_velocity = true;
  // Plausibility (per second of sensor time since the last good frame): a faster motion is a tracking failure.
  double max_speed_m_per_s = 3.0;           // handheld Kinect: fr1 peaks near 1 m/s
  double max_angular_speed_deg_per_s = 360.0;  // fr1/rpy peaks near 150 deg/s
  int max_degenerate_dims = 3;              // more unconstrained directions than this: lost
  bool integrate_poor = true;               // integrate frames whose registration is `poor`
  // Depth consistency (decide stage): the frame's depth, moved by the estimated motion, is compared with the model
  // depth it lands on (every 4th pixel). Where at least min_overlap of the sampled pixels land on the model, at
  // least min_consistent of those must agree within 3 sigma of the Kinect axial noise (Nguyen et al. 2012) plus
  // one voxel; else the depth is garbage (or the pose is wrong) and the frame is lost. Photometric rows can track a
  // frame whose depth is broken, so the pose alone does not protect the map.
  double min_overlap = 0.2;
  double min_consistent = 0.5;
  // Streaming (Niessner et al. 2013): blocks farther than this from the camera go to the host store after each
  // frame; 0 = off.
  double stream_radius_m = 0.0;

  // Throws hf::Error naming the bad field (also validates the nested option structs).
  void validate() const;
};

// JSON form of the whole configuration (written into report.json) and back. from_json starts from the defaults
// and overrides the keys present; an unknown key or a value of the wrong type throws hf::Error naming `where`
// (e.g. the config file) and the key.
nlohmann::json config_to_json(const PipelineConfig& config);
PipelineConfig config_from_json(const nlohmann::json& j, const std::string& where);
// Reads a JSON config file; errors name the file (and line for JSON syntax errors).
PipelineConfig load_config(const std::string& path);
// The same from the file's text; `name` stands for the file in messages.
PipelineConfig parse_config(const std::string& text, const std::string& name);

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
