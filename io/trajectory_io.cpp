#include "io/trajectory_io.h"

#include <cmath>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "core/atomic_file.h"
#include "core/error.h"

namespace hf {

Trajectory parse_tum_trajectory(const std::string& text, const std::string& file) {
  Trajectory out;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    const size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream ls(line);
    double v[8];
    int n = 0;
    std::string token;
    while (ls >> token) {
      if (n == 8) throw ParseError(file, lineno, "expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got more");
      char* end = nullptr;
      v[n] = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(v[n]))
        throw ParseError(file, lineno, "expected a finite number, got '" + token + "'");
      ++n;
    }
    if (n != 8) throw ParseError(file, lineno, "expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got " + std::to_string(n));
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (q.norm() < 1e-6) throw ParseError(file, lineno, "expected a non-zero quaternion");
    if (!out.empty() && !(v[0] > out.back().timestamp_s))
      throw ParseError(file, lineno, "expected timestamps strictly increasing");
    out.push_back({v[0], SE3(q, Eigen::Vector3d(v[1], v[2], v[3]))});
  }
  return out;
}

Trajectory read_tum_trajectory(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(path + ": cannot open trajectory file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse_tum_trajectory(ss.str(), path);
}

std::string format_tum_trajectory(const Trajectory& trajectory, const std::string& header) {
  std::ostringstream out;
  if (!header.empty()) {
    std::istringstream h(header);
    std::string line;
    while (std::getline(h, line)) out << "# " << line << "\n";
  }
  out << std::setprecision(17);
  for (const StampedPose& p : trajectory) {
    const auto& t = p.T_world_camera.translation();
    const auto& q = p.T_world_camera.quaternion();
    out << std::fixed << std::setprecision(6) << p.timestamp_s << std::defaultfloat << std::setprecision(17) << ' '
        << t.x() << ' ' << t.y() << ' ' << t.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w()
        << "\n";
  }
  return out.str();
}

void write_tum_trajectory(const std::string& path, const Trajectory& trajectory, const std::string& header) {
  const std::string text = format_tum_trajectory(trajectory, header);
  write_file_atomically(path, [&](std::ostream& out) { out << text; });
}

}  // namespace hf
