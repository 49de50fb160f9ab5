#include "viewer/view_controller.h"

#include <algorithm>
#include <cmath>

namespace hf::viewer {

void ViewController::key(Key k) {
  std::lock_guard<std::mutex> lock(mutex_);
  switch (k) {
    case Key::pause:
      paused_ = !paused_;
      break;
    case Key::step:
      if (paused_) ++steps_;
      break;
    case Key::save_mesh:
      save_ = true;
      break;
    case Key::quit:
      quit_.store(true);
      break;
    case Key::follow:
      follow_ = !follow_;
      break;
    case Key::reset_view:
      yaw_ = 0.0;
      pitch_ = -0.35;
      distance_m_ = 2.5;
      follow_ = true;
      break;
  }
  changed_.notify_all();
}

void ViewController::drag(double dx, double dy) {
  // 0.3 degrees per pixel: a 600-pixel drag turns the view by half a circle.
  yaw_ += dx * 0.3 * M_PI / 180.0;
  pitch_ = std::clamp(pitch_ - dy * 0.3 * M_PI / 180.0, -1.5, 1.5);
  follow_ = false;
}

void ViewController::scroll(double notches) {
  distance_m_ = std::clamp(distance_m_ * std::pow(0.9, notches), 0.1, 100.0);
}

void ViewController::reset(const SE3& T_world_camera) {
  target_ = T_world_camera * Eigen::Vector3d(0, 0, 1.5);
  // Yaw and pitch are relative to the tracked camera's own axes, so "behind and above" follows it.
  const Eigen::Vector3d forward = T_world_camera.rotation().col(2);
  yaw_ = std::atan2(forward.x(), forward.z());
  pitch_ = -0.35;
}

SE3 ViewController::T_world_view() const {
  // Direction from the target back to the eye, in a y-down world (the first camera's frame).
  const Eigen::Vector3d forward(std::sin(yaw_) * std::cos(pitch_), -std::sin(pitch_),
                                std::cos(yaw_) * std::cos(pitch_));
  const Eigen::Vector3d eye = target_ - distance_m_ * forward;
  const Eigen::Vector3d z = forward.normalized();
  Eigen::Vector3d x = Eigen::Vector3d(0, 1, 0).cross(z);  // y down: right = down x forward
  if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix4d T = Eigen::Matrix4d::Identity();
  T.block<3, 1>(0, 0) = x;
  T.block<3, 1>(0, 1) = y;
  T.block<3, 1>(0, 2) = z;
  T.block<3, 1>(0, 3) = eye;
  return SE3::from_matrix(T);
}

void ViewController::wait_for_turn() {
  while (!wait_for_turn_for(std::chrono::hours(1))) {
  }
}

bool ViewController::wait_for_turn_for(std::chrono::milliseconds timeout) {
  std::unique_lock<std::mutex> lock(mutex_);
  if (!changed_.wait_for(lock, timeout, [this] { return !paused_ || steps_ > 0 || quit_.load() || released_; }))
    return false;
  if (paused_ && steps_ > 0) --steps_;
  return true;
}

bool ViewController::paused() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return paused_;
}

bool ViewController::take_save_request() {
  std::lock_guard<std::mutex> lock(mutex_);
  const bool s = save_;
  save_ = false;
  return s;
}

void ViewController::release() {
  std::lock_guard<std::mutex> lock(mutex_);
  released_ = true;
  changed_.notify_all();
}

}  // namespace hf::viewer
