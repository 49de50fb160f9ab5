// Trajectories in TUM format: one pose per line, "timestamp tx ty tz qx qy qz qw", '#' comments and blank lines
// allowed, fields separated by any whitespace. The pose is T_world_camera (camera centre and orientation in the
// world), as in TUM's groundtruth.txt.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/se3.h"

namespace hf {

struct StampedPose {
  double timestamp_s = 0.0;
  SE3 T_world_camera;
};
using Trajectory = std::vector<StampedPose>;

// Limits on untrusted trajectories: a coordinate beyond 1e6 m or a stamp beyond 1e12 s is no physical pose (and
// would overflow the metrics' squares); a line over kMaxLineBytes (core/bounded_read.h) or more poses than
// kMaxTrajectoryPoses (5.5 hours at 100 Hz, 128 MiB in memory) is refused, naming the limit.
inline constexpr double kMaxCoordinateM = 1e6;
inline constexpr double kMaxTimestampS = 1e12;
inline constexpr size_t kMaxTrajectoryPoses = 2'000'000;

// Throws hf::ParseError "FILE:LINE: expected 8 numbers ..." for a malformed line, a non-finite value, a value beyond
// the limits above, a zero quaternion, or a timestamp that is not strictly increasing (the readers and evaluation
// rely on sorted stamps). Offending tokens are quoted with quote_for_message (short, printable). read_tum_trajectory
// reads only a regular file (core/bounded_read.h): a folder, FIFO or device is an hf::Error naming it.
Trajectory read_tum_trajectory(const std::string& path);
Trajectory parse_tum_trajectory(const std::string& text, const std::string& name_for_errors);

// One pose typed by a person, "tx ty tz qx qy qz qw" (T_world_camera, TUM's order without the stamp; e.g.
// `view --camera-pose`): the same checks as a trajectory line (finite numbers, coordinates within kMaxCoordinateM,
// a non-zero quaternion, normalised). Throws hf::Error "WHAT: expected 7 numbers 'tx ty tz qx qy qz qw', got ..."
// naming the offending token; `what` says where the text came from.
SE3 parse_tum_pose(const std::string& text, const std::string& what);

// Writes atomically with full double precision; `header` lines are written as '# ' comments.
void write_tum_trajectory(const std::string& path, const Trajectory& trajectory, const std::string& header = "");
std::string format_tum_trajectory(const Trajectory& trajectory, const std::string& header = "");

}  // namespace hf
