// Trajectories in TUM format: one pose per line, "timestamp tx ty tz qx qy qz qw", '#' comments and blank lines
// allowed, fields separated by any whitespace. The pose is T_world_camera (camera centre and orientation in the
// world), as in TUM's groundtruth.txt.
#pragma once

#include <string>
#include <vector>

#include "core/se3.h"

namespace hf {

struct StampedPose {
  double timestamp_s = 0.0;
  SE3 T_world_camera;
};
using Trajectory = std::vector<StampedPose>;

// Throws hf::ParseError "FILE:LINE: expected 8 numbers ..." for a malformed line, a non-finite value, a zero
// quaternion, or a timestamp that is not strictly increasing (the readers and evaluation rely on sorted stamps).
Trajectory read_tum_trajectory(const std::string& path);
Trajectory parse_tum_trajectory(const std::string& text, const std::string& name_for_errors);

// Writes atomically with full double precision; `header` lines are written as '# ' comments.
void write_tum_trajectory(const std::string& path, const Trajectory& trajectory, const std::string& header = "");
std::string format_tum_trajectory(const Trajectory& trajectory, const std::string& header = "");

}  // namespace hf
