// The window that follows a run (`hashfusion run ... --view`) and its headless twin (`--screenshot FILE.png`,
// `--screenshot-every N`).
//
// The tracking thread calls observe() after each frame. It only copies what the view needs into a snapshot under
// a mutex (the input colour and depth, the pose and state, one point in 64 of an integrated frame back-projected
// into the world as the growing model, the status line), so tracking never waits for rendering; the window thread
// redraws from the latest snapshot at its own rate (about 30 Hz): on the left the model points, the trajectory
// (green, lost frames marked red) and the current camera frustum (yellow) from a free camera; on the right the
// input colour and depth; the status (frame, state, fps per stage, blocks, memory, paused) in the title bar.
// Keys and mouse: viewer/view_controller.h. After the last frame finish() shows the final mesh; a window stays
// open until closed, a headless viewer writes its screenshot and returns.
// Screenshots (headless): --screenshot-every N writes FILE_NNNNNN.png (N-th frames, the free camera's view of the
// model so far) and --screenshot FILE.png the final mesh from the last pose: the same view as render.png of a run
// but rendered by OpenGL. finish() waits until every requested screenshot is written.
// Failures: hf::Error when no display / GL context exists (one line, see gl_context.h), raised by the constructor.
// This header includes no GL.
#pragma once

#include <memory>
#include <string>

#include "core/camera.h"
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

  // Tracking thread: cheap copies only (see above). `blocks` and `memory_bytes` are the map's, for the status line.
  void observe(const RgbdFrame& frame, const slam::FrameResult& result, size_t blocks, size_t memory_bytes);
  ViewController& controller();
  // After the run: the final mesh from `T_world_camera` (the last good pose). Blocks until the window is closed
  // (interactive) or every screenshot is written (headless). Throws hf::Error when a screenshot cannot be written.
  void finish(const TriangleMesh& mesh, const SE3& T_world_camera);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// A screenshot path for frame `index`: "shots/v.png" -> "shots/v_000120.png".
std::string numbered_screenshot(const std::string& path, long index);

}  // namespace hf::viewer
