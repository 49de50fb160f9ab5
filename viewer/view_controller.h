// What the viewer's keys and mouse do, apart from any window (so tests drive it without a display):
//   space  pause / resume the run          n  one frame while paused     r  reset the view
//   s      save the mesh now (OUT/mesh_view_N.ply)                      f  follow the tracked camera on / off
//   q, Esc end the run (its outputs are written as after Ctrl-C)
//   left drag  orbit around the target     scroll  zoom (distance x 0.9 per notch)
// The free camera orbits `target` at `distance_m`, yaw about the world's -y axis (the cameras' "up" is -y in
// the camera convention) and pitch; reset() puts it behind and above the given pose, looking at the point 1.5 m in
// front of that camera.
// Thread-safety: the run-control half (wait_for_turn, take_save_request, quit_requested) is called from the
// tracking thread while the window thread feeds keys; both halves lock one mutex. The camera half is for the
// window thread only.
#pragma once

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>

#include "core/se3.h"

namespace hf::viewer {

enum class Key { pause, step, reset_view, save_mesh, follow, quit };

class ViewController {
 public:
  void key(Key k);
  void drag(double dx_px, double dy_px);  // left button held
  void scroll(double notches);
  void reset(const SE3& T_world_camera);
  SE3 T_world_view() const;  // the free camera's pose (camera convention: x right, y down, z forward)
  bool follow() const { return follow_; }

  // Tracking thread, after each frame: blocks while paused (until resumed, a step, quit or release()), so pausing
  // holds the run where the user asked; otherwise returns at once.
  void wait_for_turn();
  // The same for at most `timeout`: true when the run may go on, false when it is still held (the caller does
  // something else, e.g. renders for a paused run's window, and asks again).
  bool wait_for_turn_for(std::chrono::milliseconds timeout);
  bool paused() const;
  bool take_save_request();  // true once per 's'
  const std::atomic<bool>* quit_flag() const { return &quit_; }
  void release();  // the window closed: never block the run again

 private:
  mutable std::mutex mutex_;
  std::condition_variable changed_;
  bool paused_ = false, released_ = false, save_ = false;
  long steps_ = 0;
  std::atomic<bool> quit_{false};
  bool follow_ = true;
  Eigen::Vector3d target_{0, 0, 1.5};
  double yaw_ = 0.0, pitch_ = -0.35, distance_m_ = 2.5;
};

}  // namespace hf::viewer
