#include "bench/harness/peers.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <optional>

#include "core/error.h"
#include "core/progress.h"
#include "core/timing.h"

#ifdef HF_BENCH_HAVE_PCL
#include "bench/pcl_reference.h"
#endif
#ifdef HF_BENCH_HAVE_OPEN3D
#include "bench/open3d_reference.h"
#endif

namespace hf::bench {

std::vector<std::string> peer_names() {
  std::vector<std::string> names;
#ifdef HF_BENCH_HAVE_PCL
  names.insert(names.end(), {"gicp", "ndt"});
#endif
#ifdef HF_BENCH_HAVE_OPEN3D
  for (const std::string& m : open3d_methods()) names.push_back(m);
#endif
  return names;
}

void PeerOptions::validate() const {
  if (!(voxel_m > 0.0f && voxel_m <= 1.0f)) throw Error("peer voxel_m must be in (0, 1] m, got " + std::to_string(voxel_m));
  if (!(ndt_resolution_m > 0.0f && ndt_resolution_m <= 10.0f)) {
    throw Error("peer ndt_resolution_m must be in (0, 10] m, got " + std::to_string(ndt_resolution_m));
  }
  if (pixel_stride < 1 || pixel_stride > 64) {
    throw Error("peer pixel_stride must be in 1..64, got " + std::to_string(pixel_stride));
  }
  if (!(max_speed_m_per_s > 0.0) || !(max_angular_speed_deg_per_s > 0.0)) {
    throw Error("peer speed limits must be positive");
  }
  if (min_points < 3) throw Error("peer min_points must be at least 3, got " + std::to_string(min_points));
}

long PeerRun::frames_lost() const {
  long n = 0;
  for (const PeerFrame& f : frames) n += f.pose_valid ? 0 : 1;
  return n;
}

Trajectory PeerRun::estimate() const {
  Trajectory t;
  for (const PeerFrame& f : frames) {
    if (f.pose_valid) t.push_back({f.timestamp_s, f.T_world_camera});
  }
  return t;
}

std::vector<Eigen::Vector3f> backproject_depth(const DepthImage& depth, const PinholeCamera& camera, int stride) {
  if (stride < 1) throw Error("backproject_depth: stride must be >= 1, got " + std::to_string(stride));
  std::vector<Eigen::Vector3f> points;
  points.reserve(size_t(depth.width() / stride + 1) * size_t(depth.height() / stride + 1));
  for (int y = 0; y < depth.height(); y += stride) {
    for (int x = 0; x < depth.width(); x += stride) {
      const float d = depth(x, y);
      if (d > 0.0f && std::isfinite(d)) points.push_back(camera.backproject(x, y, d).cast<float>());
    }
  }
  return points;
}

PeerRun run_peer(FrameSource& source, const std::string& method, const PeerOptions& options, long max_frames,
                 const std::atomic<bool>* stop, const std::string& progress_label) {
  options.validate();
  const bool open3d = method.rfind("o3d-", 0) == 0;
  if (method != "gicp" && method != "ndt" && method != "o3d-icp" && method != "o3d-colored-icp" &&
      method != "o3d-rgbd") {
    throw Error("unknown peer '" + method + "' (known: gicp, ndt, o3d-icp, o3d-colored-icp, o3d-rgbd)");
  }
  const std::vector<std::string> built = peer_names();
  if (std::find(built.begin(), built.end(), method) == built.end()) {
    throw Error("peer '" + method + "' needs " + (open3d ? "Open3D" : "PCL") +
                ", which this build of hashfusion does not have");
  }
#if !defined(HF_BENCH_HAVE_PCL) && !defined(HF_BENCH_HAVE_OPEN3D)
  (void)source;
  (void)max_frames;
  (void)stop;
  (void)progress_label;
  return {};
#else
  const PinholeCamera& camera = source.camera();
  const long total = max_frames > 0 ? std::min<long>(max_frames, long(source.size())) : long(source.size());
  std::unique_ptr<Progress> progress;
  if (!progress_label.empty()) progress = std::make_unique<Progress>(progress_label, total);

  PeerRun run;
  std::vector<Eigen::Vector3f> target;  // the last good frame's cloud (camera frame)
  DepthImage target_depth;              // and its images (Open3D's peers build their own clouds from them)
  ColorImage target_color;
  std::optional<SE3> last_good;
  double last_good_time_s = 0.0;
  SE3 velocity;          // T_prev_cur of the last accepted consecutive pair
  bool have_velocity = false;
  long read = 0;
  while (read < total) {
    if (stop && stop->load()) {
      run.interrupted = true;
      break;
    }
    const auto t_read = std::chrono::steady_clock::now();
    FrameRead r = source.next();
    const double ms_read = ms_since(t_read);
    if (r.status == FrameStatus::end) break;
    ++read;
    if (r.status == FrameStatus::bad_frame) {
      ++run.frames_bad;
      if (progress) progress->update(read, "bad frame");
      continue;
    }
    PeerFrame f;
    f.index = r.frame.index;
    f.timestamp_s = r.frame.timestamp_s;
    f.ms_read = ms_read;
    const auto t_pre = std::chrono::steady_clock::now();
    std::vector<Eigen::Vector3f> cloud = backproject_depth(r.frame.depth, camera, options.pixel_stride);
    f.ms_preprocess = ms_since(t_pre);

    if (!last_good) {
      f.T_world_camera = r.frame.T_world_camera_gt.value_or(SE3());
      if (long(cloud.size()) >= options.min_points) {
        f.pose_valid = true;
        last_good = f.T_world_camera;
        last_good_time_s = f.timestamp_s;
        target = std::move(cloud);
        target_depth = std::move(r.frame.depth);
        target_color = std::move(r.frame.color);
      } else {
        f.message = "too few depth points (" + std::to_string(cloud.size()) + ") to start";
      }
    } else if (long(cloud.size()) < options.min_points) {
      f.T_world_camera = *last_good;
      f.message = "too few depth points (" + std::to_string(cloud.size()) + ")";
      have_velocity = false;
    } else {
      const bool after_gap = !run.frames.empty() && !run.frames.back().pose_valid;
      const SE3 guess = options.constant_velocity && have_velocity && !after_gap ? velocity : SE3();
      const auto t_track = std::chrono::steady_clock::now();
      std::optional<SE3> T_prev_cur;
      const std::string library = open3d ? "Open3D" : "PCL";
      try {
        bool converged = false;
        SE3 T;
        if (open3d) {
#ifdef HF_BENCH_HAVE_OPEN3D
          const Open3dOptions o3{.voxel_m = options.voxel_m, .pixel_stride = options.pixel_stride};
          const Open3dAlignResult res = open3d_align(method, r.frame.depth, r.frame.color, target_depth,
                                                     target_color, camera, guess.matrix(), o3);
          converged = res.converged;
          T = SE3::from_matrix(res.T_target_source);
#endif
        } else {
#ifdef HF_BENCH_HAVE_PCL
          // PCL starts at the identity: the source goes in moved by the guess.
          std::vector<Eigen::Vector3f> moved = cloud;
          const Eigen::Matrix3f R = guess.rotation().cast<float>();
          const Eigen::Vector3f t = guess.translation().cast<float>();
          for (Eigen::Vector3f& p : moved) p = R * p + t;
          const PclAlignResult res = pcl_align(method, moved, target, options.voxel_m, options.ndt_resolution_m);
          converged = res.converged;
          T = SE3::from_matrix(res.T_target_source) * guess;
#endif
        }
        if (!converged) {
          f.message = library + " " + method + " did not converge";
        } else if (!T.is_finite()) {
          f.message = library + " " + method + " returned a non-finite pose";
        } else {
          T_prev_cur = T;
        }
      } catch (const std::exception& e) {
        f.message = library + " " + method + " threw: " + e.what();
      }
      f.ms_track = ms_since(t_track);
      if (T_prev_cur) {
        const double dt = std::max(f.timestamp_s - last_good_time_s, 1e-3);
        const double speed = T_prev_cur->translation().norm() / dt;
        const double angular = T_prev_cur->angle_rad() * 180.0 / M_PI / dt;
        if (speed > options.max_speed_m_per_s || angular > options.max_angular_speed_deg_per_s) {
          f.message = "implausible motion (" + std::to_string(speed) + " m/s, " + std::to_string(angular) + " deg/s)";
          T_prev_cur.reset();
        }
      }
      if (T_prev_cur) {
        f.T_world_camera = *last_good * *T_prev_cur;
        f.pose_valid = true;
        velocity = *T_prev_cur;
        have_velocity = !after_gap;
        last_good = f.T_world_camera;
        last_good_time_s = f.timestamp_s;
        target = std::move(cloud);
        target_depth = std::move(r.frame.depth);
        target_color = std::move(r.frame.color);
      } else {
        f.T_world_camera = *last_good;
        have_velocity = false;
      }
    }
    run.frames.push_back(std::move(f));
    if (progress) {
      const long lost = run.frames_lost();
      progress->update(read, lost ? "lost " + std::to_string(lost) : "good");
    }
  }
  if (progress) progress->finish();
  return run;
#endif
}

}  // namespace hf::bench
