// Fuzzes TUM trajectory parsing: a parsed trajectory has strictly increasing stamps and finite unit-quaternion
// poses within the physical bounds, and formatting it and parsing the text again gives back the same stamps and
// poses exactly. Every failure is a ParseError whose message is short and printable; a first line over the length
// limit is always refused on line 1.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/error.h"
#include "io/trajectory_io.h"
#include "tests/io/fuzz_message_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  hf::Trajectory t;
  try {
    t = hf::parse_tum_trajectory(text, "fuzz.txt");
  } catch (const hf::ParseError& e) {
    if (e.file() != "fuzz.txt" || e.line() < 1) std::abort();
    hf::fuzz::check_message(e, "fuzz.txt");
    t.clear();
  }
  hf::fuzz::check_long_first_line_refused(text, [](const std::string& t) { hf::parse_tum_trajectory(t, "long.txt"); });
  if (t.size() > hf::kMaxTrajectoryPoses) std::abort();
  for (size_t i = 0; i < t.size(); ++i) {
    if (!t[i].T_world_camera.is_finite() || std::fabs(t[i].T_world_camera.quaternion().norm() - 1.0) > 1e-9)
      std::abort();
    if (i > 0 && !(t[i - 1].timestamp_s < t[i].timestamp_s)) std::abort();
    if (t[i].T_world_camera.translation().cwiseAbs().maxCoeff() > hf::kMaxCoordinateM) std::abort();
    if (std::fabs(t[i].timestamp_s) > hf::kMaxTimestampS) std::abort();
  }
  const hf::Trajectory back = hf::parse_tum_trajectory(hf::format_tum_trajectory(t, "round trip"), "round-trip");
  if (back.size() != t.size()) std::abort();
  for (size_t i = 0; i < t.size(); ++i) {
    if (back[i].timestamp_s != t[i].timestamp_s) std::abort();
    if (back[i].T_world_camera.translation() != t[i].T_world_camera.translation()) std::abort();
    if ((back[i].T_world_camera.matrix() - t[i].T_world_camera.matrix()).cwiseAbs().maxCoeff() > 1e-12) std::abort();
  }
  return 0;
}
