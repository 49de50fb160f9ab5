// The window that follows a run (`hashfusion run ... --view`) and its headless twin (`--screenshot FILE.png`,
// `--screenshot-every N`).
//
// The tracking thread calls observe() after each frame and hold() before the next. observe() copies what the view
// needs into a snapshot under a mutex (the input colour and depth, the pose and state, the status line), and,
// between frames while the map is not being modified, renders the model: a raycast of the TSDF shaded in its fused
// colours (fusion/raycast.h, model_view_options()) from the free camera's pose, what the window asked for last, at
// most kModelViewMaxPx on its longer side, at most kModelViewHz times a second and only after a pause of 1 /
// kModelViewShare times the last one's cost, so the raycasts take at most that share of the tracking thread's time
// (what one costs: bench/results/viewer.md). The window thread redraws at its own rate (about 30 Hz) from
// the latest snapshot: on the left the model raycast, the trajectory (green, lost frames marked red) and the
// current camera frustum (yellow), each line hidden where the model's surface is nearer; on the right the input
// colour and depth; the status (frame, state, fps per stage, blocks, memory, paused) in the title bar. While the
// run is paused hold() keeps rendering the model for the window, so orbiting a paused run still shows it.
// Keys and mouse: viewer/view_controller.h. After the last frame finish() shows the final mesh; a window stays
// open until closed, a headless viewer writes its screenshots and returns.
// Screenshots (headless): --screenshot-every N writes FILE_NNNNNN.png every N-th frame: the model raycast from
// the following free camera (ViewController::reset of that frame's pose) with the input camera's intrinsics, the
// trajectory so far and the frustum, exactly what the window's model view shows; --screenshot FILE.png the final
// mesh from the last pose: the same view as render.png of a run but rendered by OpenGL. finish() waits until every
// requested screenshot is written.
// Failures: hf::Error when no display / GL context exists (one line, see gl_context.h), raised by the constructor.
// This header includes no GL.
#pragma once

#include <memory>
#include <string>

#include "core/camera.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"
#include "io/frame_source.h"
#include "io/mesh.h"
#include "slam/pipeline.h"
#include "viewer/view_controller.h"

namespace hf::viewer {

struct RunViewerOptions {
  bool window = true;          // false: headless, screenshots only
  std::string screenshot;      // final view of the mesh from the last pose (PNG)
  long screenshot_every = 0;   // every N frames: screenshot with "_NNNNNN" before the extension
  std::string out_dir;         // where 's' saves mesh_view_N.ply
};

class RunViewer {
 public:
  // Starts the window thread and waits until its GL context exists; throws hf::Error when it cannot.
  RunViewer(const PinholeCamera& camera, const RunViewerOptions& options);
  ~RunViewer();
  RunViewer(const RunViewer&) = delete;
  RunViewer& operator=(const RunViewer&) = delete;

  // Tracking thread, after each frame, with the map as the frame left it (see above).
  void observe(const RgbdFrame& frame, const slam::FrameResult& result, const fusion::VoxelBlockGrid& map);
  // Tracking thread, before the next frame: returns when the run may go on (ViewController::wait_for_turn),
  // rendering the model for the window meanwhile. `map` must not change until it returns.
  void hold(const fusion::VoxelBlockGrid& map);
  ViewController& controller();
  // After the run: the final mesh from `T_world_camera` (the last good pose). Blocks until the window is closed
  // (interactive) or every screenshot is written (headless). Throws hf::Error when a screenshot cannot be written.
  void finish(const TriangleMesh& mesh, const SE3& T_world_camera);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

inline constexpr double kModelViewHz = 15.0;
inline constexpr double kModelViewShare = 0.2;
inline constexpr int kModelViewMaxPx = 640;

// The raycast the model view uses: the defaults of fusion::RaycastOptions (shading and colour, shown as
// fusion::colored_shading), rays out to 20 m (the free camera stands back from the scene) and the crossing refined
// to 0.05 voxel (the pipeline's tracking raycast's tolerance: far below a pixel at any distance shown).
fusion::RaycastOptions model_view_options();

// A screenshot path for frame `index`: "shots/v.png" -> "shots/v_000120.png".
std::string numbered_screenshot(const std::string& path, long index);

}  // namespace hf::viewer
