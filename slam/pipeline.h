// The dense RGB-D SLAM pipeline: one frame in, one tracked pose and an updated map out (KinectFusion's loop over
// the voxel-hashed TSDF, with the registration method chosen by name).
//
//   hf::slam::Pipeline p(config, camera);
//   for (each frame) { hf::slam::FrameResult r = p.process(frame); ... }
//   hf::TriangleMesh mesh = p.extract_mesh();
//
// Stages of process(), each a function of its own, timed into FrameResult::ms (the caller times `read`):
//   preprocess   frame pyramid of the new frame: bilateral-filtered depth, vertices, normals, intensity, gradients.
//   track        align the frame to the reference: the model raycast at the last pose for the geometric rows
//                (frame-to-model, KinectFusion) and the previous frame's intensity for the photometric rows
//                (frame-to-frame: the report, section 3.2, finds the model colour too blurred to track against).
//                Both live in the camera frame of the last pose, so T_world_cur = T_world_ref * T_ref_cur. When
//                that fails or disagrees with the map, fallback_registration (icp) is tried against the same model.
//                With seed_registration set (sparse), it runs first and its estimate becomes the initial guess
//                where it disagrees with the motion prior (large motion). Where neither placed the frame,
//                seed_on_failure (sparse) runs once and, from its estimate where that is plausible, the primary
//                (then the fallback) runs again: the wide baseline costs the seed on rejected frames only.
//                While the primary reads colour, every few frames the colour is checked against the depth
//                (slam/colour_check.h, timed into `track`); once it is judged not registered to the depth,
//                colour_check.depth_only_registration tracks from the next frame on.
//   decide       the verdict (Verdict) from the registration results, computed before any state changes:
//                integrate, odometry or lose (the failure policy below).
//   relocalise   only for a frame the verdict loses, once keyframes exist: the frame is registered against the
//                keyframes its appearance retrieves (slam/appearance.h) and the best is verified against the map.
//   integrate    fuse the frame into the TSDF at its pose (integrate verdicts only).
//   raycast      the model maps at the new pose: the next frame's reference.
//   keyframe     an integrated frame is compressed once (slam/keyframes.h CompressedRgbd) and kept for re-fusion
//                (slam/reintegration.h); one that moved far enough from the last keyframe becomes a keyframe and
//                is added to the appearance index, which retrieves its loop candidates' appearance matches now
//                (the index belongs to this thread). The compression runs on a worker thread while the next frame
//                is processed (it is single-threaded PNG + JPEG work, ~11-14 ms at 640x480, beside stages that
//                are not); the images join the keyframe and the re-fusion store before anything reads them.
//   close_loops  the back-end (slam/backend.h), beside tracking on the thread "hf-backend": once no job is in
//                flight and new keyframes have their images, a job takes a snapshot of the keyframe poses, the
//                loops and the new keyframes (their images and appearance matches) after frame s, and is applied
//                before frame s + loop_closure.apply_delay_frames is tracked, the tracker waiting there only if it
//                is late (realtime mode: applied at the first frame boundary after it is done, never waited for). Per new keyframe the job registers its odometry edge against the
//                previous keyframe's own images (independent of the map, so the chain keeps the drift a loop must
//                remove), verifies loop candidates by appearance and pose proximity by registration (from the
//                poses' relative guess, then inlier ratio and depth agreement), and solves the keyframe pose graph
//                when a loop was verified (slam/loop_closure.h, slam/pose_graph.h). Applying it: the keyframes take
//                the solution (those made after the snapshot, the current pose and the tracking reference move
//                rigidly with the snapshot's newest keyframe), and the fused frames whose anchored pose moved are
//                queued for re-fusion, the most-changed reintegration.frames_after_loop of them at once.
//   reintegrate  between frames, queued frames (most-changed first) are taken out of the map at the pose they were
//                fused at and fused again at their corrected one (slam/reintegration.h): frames_per_step per frame
//                (offline, so results stay exact), or as many as fit budget_ms_per_frame (realtime mode).
//
// The tracking thread's back-end work per frame is thus bounded by the view, not by the session: an appearance
// query on keyframes, the job's snapshot (copies of keyframe poses: O(keyframes), microseconds), applying a result
// (O(keyframes + fused frames) pose products), and the re-fusion budget. The cost that grows with the session
// (verification, graph solves) runs on the back-end; it holds a frame only when it is later than
// apply_delay_frames (FrameResult::ms.loop says how long).
//
// Poses: FrameResult::T_world_camera is the ONLINE estimate, the pose known when the frame was processed.
// corrected_trajectory() gives every processed frame's pose after the loop closures so far (each frame moves with
// the keyframe it was tracked from); finish() drains the re-fusion queue, finish(true) (`--global`) solves the
// whole graph once more and fuses the map anew from the final poses.
//
// Failure policy (it lives here, not in registration). A registration is PLAUSIBLE when it is usable, degenerate
// in at most max_degenerate_dims directions and implies a motion below max_speed_m_per_s /
// max_angular_speed_deg_per_s since the last pose; it is CONSISTENT when the frame's depth agrees with the model
// depth where they overlap (min_overlap, min_consistent). Then:
//   - plausible and consistent (primary or fallback, from the motion prior or, where neither was, retried from
//     seed_on_failure's estimate): TRACKED (RECOVERED after lost frames), integrated;
//   - plausible but not consistent, while not lost: ODOMETRY: the pose moves to the estimate and the reference is
//     raycast there with the frame's intensity, but nothing is integrated (a frame not trusted enough to integrate
//     must not freeze the pose, yet must not touch the map);
//   - otherwise LOST: not integrated, the pose stays at the last estimate, `pose_valid` is false; the next frame is
//     tracked against the same reference with no motion prior and, failing that, relocalised against the
//     keyframes (RELOCALISED when that succeeds). A bad frame never touches the map.
// FrameResult::T_world_camera always holds the pose the run reports for the frame (for a lost frame: the last
// estimate), so a trajectory of every frame can be written and judged honestly.
//
// The first frame (or the first after the map was empty) is placed at its ground-truth pose when the dataset has
// one, else at the identity, and integrated without tracking: the map then lives in the ground-truth world frame,
// which makes meshes directly comparable with the scene (ATE aligns trajectories anyway).
//
// `registration = "groundtruth"` skips tracking and uses each frame's ground-truth pose (fusion-only runs);
// frames without ground truth are then lost.
//
// Thread-safety: one process() at a time; it uses all cores itself. The back-end thread touches no state of the
// pipeline (it works on copies and its own LoopCloser); the map and keyframes change only inside process() and
// finish(), on the caller's thread.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <future>
#include <map>
#include <memory>
#include <optional>
#include <string>

#include "core/camera.h"
#include "core/se3.h"
#include "core/undistort.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/streaming.h"
#include "fusion/voxel_block_grid.h"
#include "io/frame_source.h"
#include "io/mesh.h"
#include "io/trajectory_io.h"
#include "registration/frame_pyramid.h"
#include "registration/registration.h"
#include "slam/appearance.h"
#include "slam/backend.h"
#include "slam/keyframes.h"
#include "slam/loop_closure.h"
#include "slam/pipeline_config.h"
#include "slam/reintegration.h"

namespace hf::fusion {
class DeviceVoxelGrid;  // fusion/opencl/device_voxel_grid.h
}
namespace hf::opencl {
class DeviceFramePyramid;  // registration/opencl/device_pyramid.h
}

namespace hf::slam {

enum class TrackState {
  initialised,  // first frame: placed (ground truth or identity) and integrated
  tracked,      // registration accepted
  recovered,    // accepted after one or more lost frames
  relocalised,  // lost before, placed by registration against a keyframe and verified against the map; integrated
  odometry,     // pose estimated but the frame disagrees with the map: not integrated (see the failure policy)
  lost,         // rejected by the failure policy: not integrated, pose = the last estimate
  groundtruth,  // pose from the dataset (registration = groundtruth)
};
const char* to_string(TrackState state);

// Milliseconds per stage for one frame (0 for stages that did not run).
struct StageMs {
  double read = 0, preprocess = 0, track = 0, relocalise = 0, integrate = 0, raycast = 0, keyframe = 0, loop = 0,
         reintegrate = 0;
  double undistort = 0;  // part of preprocess: a distorted camera's remap (core/undistort.h)
  double total() const {
    return read + preprocess + track + relocalise + integrate + raycast + keyframe + loop + reintegrate;
  }
};

struct FrameResult {
  size_t index = 0;
  double timestamp_s = 0.0;
  TrackState state = TrackState::lost;
  SE3 T_world_camera;        // the estimate; while lost, the last estimate (the pose the run reports)
  bool pose_valid = false;   // false while lost (and for groundtruth frames without ground truth)
  bool integrated = false;
  bool keyframe = false;     // the frame became a keyframe
  bool loop_closed = false;  // a verified loop at this keyframe moved the keyframes
  size_t reintegrated = 0;   // earlier frames re-fused at their corrected poses during this frame
  size_t refusion_backlog = 0;  // frames still queued for re-fusion after this frame (FusedFrames::pending)
  bool loop_applied = false;    // a back-end job's result was applied before this frame was tracked
  double backend_job_ms = 0.0;  // that job's own time on the back-end thread (not on this frame's)
  std::string method;        // the registration that placed the frame (primary, fallback, or "relocalisation")
  std::optional<RegistrationResult> registration;  // the one that placed (or failed to place) the frame
  std::string message;       // why the frame was lost (one line), empty otherwise
  // seed_on_failure ran on this frame (neither the primary nor the fallback placed it from the motion prior, or the
  // frame had no motion prior and the seed cross-checked the wide basin), and whether the retry from its estimate
  // is what placed the frame.
  bool seeded_on_failure = false;
  bool placed_by_seed = false;
  // The frame had no motion prior and the primary ran with the wide basin (PipelineConfig::wide_basin_without_prior).
  bool wide_basin = false;
  // The primary registration's two terms' disagreement (slam/colour_check.h); valid only when it has an icp and
  // a photometric term.
  TermDisagreement term_disagreement;
  // The colour-to-depth alignment estimated on this frame for the colour check (frames it sampled only).
  std::optional<ColourAlignment> colour_alignment;
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
  // With a distorted camera (PinholeCamera::distortion) the frame is first undistorted (core/undistort.h, timed
  // into `preprocess`); camera() is then the pinhole camera of the undistorted images.
  FrameResult process(const RgbdFrame& frame);

  // Realtime mode (live input, replay at the recorded rate): back-end results are applied as soon as they are
  // done, never waited for, the pose graph keeps its time budget, and re-fusion takes
  // reintegration.budget_ms_per_frame of each frame instead of frames_per_step frames. Results then depend on
  // timing. Off (the default): every result is a function of the input and the config alone.
  void set_realtime(bool realtime) { realtime_ = realtime; }
  bool realtime() const { return realtime_; }

  const PipelineConfig& config() const { return config_; }
  const PinholeCamera& camera() const { return camera_; }
  const fusion::VoxelBlockGrid& map() const { return grid_; }
  const fusion::BlockStore& store() const { return store_; }
  size_t frames_processed() const { return frames_; }
  size_t frames_lost() const { return lost_; }
  std::optional<SE3> last_good_pose() const { return T_world_cur_; }
  const KeyframeMap& keyframes() const { return keyframes_; }
  const std::vector<LoopEdge>& loops() const { return loops_; }
  size_t loops_closed() const { return loops_closed_; }
  // Keyframe window edges (loop_closure.window_keyframes), the solves they alone made, and the window pairs the
  // back-end registered (verified or not).
  const std::vector<LoopEdge>& window_edges() const { return window_; }
  size_t window_solves() const { return window_solves_; }
  size_t window_registrations() const { return window_registrations_; }
  // Whether the colour is registered to the depth, as judged so far, and the method that tracks now (the
  // configured registration, or colour_check.depth_only_registration once the colour was judged unregistered).
  const ColourCheck& colour_check() const { return colour_check_; }
  std::string tracking_registration() const { return registration_ ? registration_->name() : config_.registration; }
  const FusedFrames& fused_frames() const { return fused_; }  // the last kept frame joins it with the next

  // Continues a session in a saved map (fusion/volume_io.h: `run --save-map`, Pipeline.save): before the first
  // frame, the map replaces the empty one. The map holds the TSDF only (no keyframes, no trajectory), so nothing
  // is relocalised against it: the first frame is placed as on an empty map, at its ground-truth pose where it has
  // one, else at the map's origin (the first camera of the session that built it), and tracking goes on from
  // there against the model raycast. hf::Error when frames were processed already or the map's voxel size or
  // truncation differs from the configuration's (a TSDF cannot be resampled).
  void load_map(fusion::VoxelBlockGrid grid, fusion::BlockStore store);

  // Every processed frame's pose after the loop closures so far, in processing order.
  std::vector<SE3> corrected_trajectory() const;
  // The same with each frame's time stamp (processing order; the stamps are the frames' as given).
  Trajectory corrected_stamped_trajectory() const;
  // After the last frame: applies the back-end's job in flight and runs one more for the keyframes it has not
  // seen, then re-fuses every queued frame (the backlog ends at 0); with `global`, first solves the keyframe graph
  // once more (a longer budget) and then fuses the map anew from every stored frame at its final pose. Returns
  // the ms taken.
  double finish(bool global = false);

  // The whole map (resident and streamed-out blocks) as a welded, coloured mesh.
  TriangleMesh extract_mesh() const;
  // A shaded raycast of the model from `T_world_camera` with the pipeline's camera, for people: the head-light
  // shading modulated by the fused colour (fusion::colored_shading; grey where no colour was fused).
  ColorImage render(const SE3& T_world_camera) const;
  // Where each stage runs (report.json "devices"): preprocess, registration, integrate, raycast -> "cpu" or the
  // OpenCL device's "platform / device". backend = "opencl" integrates and casts the tracking raycast on the device
  // (fusion/opencl) unless stream_radius_m > 0 (streaming is host-only; the sampled tracking raycast stays on the
  // host too), and builds the frames' pyramids there unless the pyramid fills holes; the host map follows the
  // device's frame by frame.
  std::map<std::string, std::string> stage_devices() const;

 private:
  struct Reference;
  struct Verdict;
  FramePyramid preprocess(const RgbdFrame& frame, FrameResult* r) const;
  RgbdFrame undistort(const RgbdFrame& input, FrameResult* r) const;
  FrameResult process_pinhole(const RgbdFrame& frame, FrameResult r);
  void initialise(const RgbdFrame& frame, FramePyramid& current, FrameResult* r);
  Verdict track(const FramePyramid& current, double timestamp_s, FrameResult* r);
  Verdict register_from(Registration& primary_method, const FramePyramid& current, const SE3& guess,
                        double timestamp_s, FrameResult* r);
  RegistrationOptions wide_basin_options(const RegistrationOptions& tracking) const;
  Verdict retry_from_seed(const FramePyramid& current, const SE3& guess, double timestamp_s, Verdict failed,
                          const std::optional<RegistrationResult>& seed, FrameResult* r);
  std::optional<std::string> implausible(const RegistrationResult& reg, double timestamp_s) const;
  Verdict decide(const RegistrationResult& reg, const FramePyramid& current, double timestamp_s,
                 const std::string& method) const;
  std::optional<Verdict> relocalise(const RgbdFrame& frame, const FramePyramid& current, FrameResult* r);
  void integrate(const RgbdFrame& frame, const SE3& T_world_cur, FrameResult* r);
  void raycast_reference(FramePyramid& current, const SE3& T_world_cur, bool integrated, FrameResult* r);
  void ensure_reference_maps();
  void model_raycast(const SE3& T_world_camera, const fusion::RaycastOptions& options);
  RegistrationResult align_to_model(Registration& method, const FramePyramid& current, const SE3& guess);
  void keep_frame(const RgbdFrame& frame, FrameResult* r);
  void commit_pending_images();
  void end_frame(FrameResult* r);
  void query_loop_candidates(const RgbdFrame& frame, FrameResult* r);
  void start_loop_job(FrameResult* r);
  void finish_loop_job(bool wait, FrameResult* r);
  void apply_loop_result(const LoopJobResult& result, FrameResult* r);
  bool apply_graph(const PoseGraphOptions& options);
  void reintegrate(FrameResult* r);
  void pay_loop_refusions(FrameResult* r);
  void record_anchor(const FrameResult& r);
  void check_colour(const FramePyramid& current, FrameResult* r);
  void lose(FrameResult* r, std::string why);

  PipelineConfig config_;
  PinholeCamera camera_;           // the constructor's camera without distortion (the frames are undistorted)
  PinholeCamera tracking_camera_;  // camera_.scaled(tracking_level)
  std::unique_ptr<Undistorter> undistorter_;  // null unless the constructor's camera has distortion
  fusion::VoxelBlockGrid grid_;
  std::unique_ptr<fusion::DeviceVoxelGrid> device_map_;  // backend opencl: the map integrate() fuses into
  bool device_map_stale_ = false;  // grid_ changed on the host (re-fusion): load it before the next integrate
  std::unique_ptr<opencl::DeviceFramePyramid> device_pyramid_;  // backend opencl: the frames' tracking pyramids
  fusion::BlockStore store_;
  std::unique_ptr<Registration> registration_;  // null for groundtruth
  std::unique_ptr<Registration> fallback_;      // null when none
  std::unique_ptr<Registration> seed_;          // seed_registration; null when none
  std::unique_ptr<Registration> failure_seed_;  // seed_on_failure; null when none
  std::unique_ptr<Registration> wide_;          // the primary with the wide basin (no motion prior); null when off
  int tracking_levels_ = 0;  // levels of the frame and model pyramids: the configured ones, plus the wide basin's
  ColourCheck colour_check_;
  std::unique_ptr<Reference> reference_;        // model maps + intensity at the last pose
  KeyframeMap keyframes_;
  std::unique_ptr<AppearanceIndex> appearance_;
  std::optional<SE3> T_world_cur_;  // the last estimate (tracked, odometry or relocalised)
  double last_time_s_ = 0.0;
  FusedFrames fused_;
  std::vector<LoopEdge> loops_;
  size_t loops_closed_ = 0;
  std::vector<LoopEdge> window_;  // keyframe window edges (LoopJobResult::window)
  size_t window_solves_ = 0, window_registrations_ = 0;
  // The last kept frame while its images are compressed on a worker thread (keep_frame).
  struct KeptImages {
    CompressedRgbd images;
    float max_depth_m = 0.0f;  // the farthest depth integrated (slam/reintegration.h FusedFrames::add)
  };
  struct PendingImages {
    std::future<KeptImages> images;
    size_t correction = 0;  // corrections_ when it was kept: a correction since then re-schedules re-fusion
    std::optional<size_t> keyframe;  // the keyframe it made, if any
    size_t frame_index = 0, anchor = 0;
    SE3 T_world_anchor, T_world_frame;  // as fused (a loop closure may move the anchor before the commit)
  };
  std::optional<PendingImages> pending_images_;
  // The back-end (slam/backend.h). loop_closer_ exists when loop closure runs; backend_thread_ when it runs
  // beside tracking (loop_closure.background), else jobs run inline at their snapshot with the same results.
  std::unique_ptr<LoopCloser> loop_closer_;
  std::unique_ptr<BackendThread> backend_thread_;
  struct LoopJobInFlight {
    std::future<void> done;                 // the back-end's task (its exception comes out of get())
    std::shared_ptr<LoopJobResult> result;  // written by the task before `done` is ready, read after
    size_t apply_at_frame = 0;              // frames_ at which it is applied (offline)
  };
  std::optional<LoopJobInFlight> loop_job_;
  std::map<size_t, std::vector<AppearanceMatch>> loop_matches_;  // per keyframe not yet handed to a job
  size_t keyframes_handed_ = 0;  // keyframes [0, this) were given to a job
  size_t corrections_ = 0;       // loop results applied that moved keyframes
  size_t loop_refusions_owed_ = 0;  // offline: re-fusions still owed to the last loop (frames_after_loop)
  size_t loop_refusions_paid_at_ = 0;  // frames_ when a share was last paid (one share per frame)
  bool realtime_ = false;
  // Per processed frame: the keyframe it moves with (npos before the first) and its pose relative to it.
  struct Anchor {
    size_t keyframe;
    SE3 T_keyframe_frame;
    double timestamp_s;  // the frame's, for corrected_stamped_trajectory()
  };
  std::vector<Anchor> anchors_;
  SE3 velocity_;          // T_prev_cur of the last accepted frame pair
  double velocity_dt_s_ = 0.0;  // the sensor time velocity_ spans
  bool motion_prior_ = false;  // velocity_ is a measured motion (not the identity after a start, loss or relocalisation)
  long lost_spell_ = 0;   // consecutive lost frames up to now
  size_t frames_ = 0, lost_ = 0;
};

}  // namespace hf::slam
