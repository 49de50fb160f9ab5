#include "io/trajectory_io.h"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <iomanip>
#include <sstream>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/error.h"
#include "io/text_util.h"

namespace hf {
namespace {

// The shortest fixed-point text that parses back to exactly this double: TUM's own stamps keep their six
// decimals ("1305031229.528748"), synthetic ones (k / 30 s) lose nothing, and stamps closer than a microsecond
// stay distinct (a fixed six-decimal format would merge them and break the strictly-increasing rule on reading).
std::string format_timestamp(double t) {
  char buffer[400];
  const auto result = std::to_chars(buffer, buffer + sizeof(buffer), t, std::chars_format::fixed);
  if (result.ec != std::errc()) {
    std::ostringstream s;
    s << std::setprecision(17) << t;
    return s.str();
  }
  return std::string(buffer, result.ptr);
}

}  // namespace

Trajectory parse_tum_trajectory(const std::string& text, const std::string& file) {
  Trajectory out;
  int lineno = 0;
  for (size_t pos = 0; pos < text.size();) {
    size_t end = text.find('\n', pos);
    if (end == std::string::npos) end = text.size();
    const std::string_view line(text.data() + pos, end - pos);
    pos = end + 1;
    ++lineno;
    if (line.size() > kMaxLineBytes)
      throw ParseError(file, lineno, "expected a line of at most " + std::to_string(kMaxLineBytes) + " bytes, got " +
                                         std::to_string(line.size()));
    const std::vector<std::string_view> words = split_words(line);
    if (words.empty() || words[0][0] == '#') continue;
    if (words.size() != 8)
      throw ParseError(file, lineno, "expected 8 numbers 'timestamp tx ty tz qx qy qz qw', got " +
                                         (words.size() > 8 ? std::string("more") : std::to_string(words.size())));
    double v[8];
    for (int n = 0; n < 8; ++n) {
      const std::string token(words[size_t(n)]);
      char* stop = nullptr;
      v[n] = std::strtod(token.c_str(), &stop);
      if (stop == token.c_str() || *stop != '\0' || !std::isfinite(v[n]))
        throw ParseError(file, lineno, "expected a finite number, got " + quote_for_message(token));
    }
    if (!(std::fabs(v[0]) <= kMaxTimestampS))
      throw ParseError(file, lineno, "expected a time stamp within 1e12 s, got " + quote_for_message(words[0]));
    for (int k = 1; k <= 3; ++k)
      if (!(std::fabs(v[k]) <= kMaxCoordinateM))
        throw ParseError(file, lineno, "expected coordinates within 1e6 m (a physical bound), got " +
                                           quote_for_message(words[size_t(k)]));
    // Scale by the largest component before normalising: q.norm() overflows to inf for components near 1e155
    // (normalising by it would then give a zero quaternion, i.e. NaN rotations) and underflows for tiny ones.
    Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    const double largest = q.coeffs().cwiseAbs().maxCoeff();
    if (!(largest * (q.coeffs() / largest).norm() >= 1e-6)) throw ParseError(file, lineno, "expected a non-zero quaternion");
    q.coeffs() /= largest;
    if (!out.empty() && !(v[0] > out.back().timestamp_s))
      throw ParseError(file, lineno, "expected timestamps strictly increasing");
    if (out.size() == kMaxTrajectoryPoses)
      throw ParseError(file, lineno, "expected at most " + std::to_string(kMaxTrajectoryPoses) +
                                         " poses (the trajectory limit), got more");
    out.push_back({v[0], SE3(q, Eigen::Vector3d(v[1], v[2], v[3]))});
  }
  return out;
}

SE3 parse_tum_pose(const std::string& text, const std::string& what) {
  const std::string expected = what + ": expected 7 numbers 'tx ty tz qx qy qz qw'";
  if (text.size() > kMaxLineBytes) throw Error(expected + ", got " + std::to_string(text.size()) + " bytes");
  const std::vector<std::string_view> words = split_words(text);
  if (words.size() != 7)
    throw Error(expected + ", got " + (words.size() > 7 ? std::string("more") : std::to_string(words.size())));
  double v[7];
  for (int n = 0; n < 7; ++n) {
    const std::string token(words[size_t(n)]);
    char* stop = nullptr;
    v[n] = std::strtod(token.c_str(), &stop);
    if (stop == token.c_str() || *stop != '\0' || !std::isfinite(v[n]))
      throw Error(expected + ", got " + quote_for_message(token));
    if (n < 3 && !(std::fabs(v[n]) <= kMaxCoordinateM))
      throw Error(what + ": expected coordinates within 1e6 m, got " + quote_for_message(token));
  }
  Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  const double largest = q.coeffs().cwiseAbs().maxCoeff();  // scaled first, as in parse_tum_trajectory
  if (!(largest * (q.coeffs() / largest).norm() >= 1e-6)) throw Error(what + ": expected a non-zero quaternion");
  q.coeffs() /= largest;
  return SE3(q, Eigen::Vector3d(v[0], v[1], v[2]));
}

Trajectory read_tum_trajectory(const std::string& path) {
  return parse_tum_trajectory(read_regular_file(path, "trajectory file"), path);
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
    out << format_timestamp(p.timestamp_s) << ' '
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
