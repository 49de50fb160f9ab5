// Fuzzes the 7-Scenes pose and camera-intrinsics parsers: a result is always a finite rigid transform / a valid
// camera; every failure is an hf::ParseError with a short printable message.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/camera_bounds.h"
#include "core/error.h"
#include "io/seven_scenes.h"
#include "io/trajectory_io.h"
#include "tests/io/fuzz_message_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const hf::SE3 T = hf::parse_seven_scenes_pose(text, "pose.txt");
    if (!T.is_finite() || std::fabs(T.quaternion().norm() - 1.0) > 1e-9) std::abort();
    if (!(T.translation().cwiseAbs().maxCoeff() <= hf::kMaxCoordinateM)) std::abort();  // issue 35: 1e308 hung plots
  } catch (const hf::ParseError& e) {
    hf::fuzz::check_message(e, "pose.txt");
  }
  try {
    const hf::PinholeCamera c = hf::parse_seven_scenes_intrinsics(text, "camera-intrinsics.txt");
    if (!(c.fx > 0.0) || !(c.fy > 0.0) || !std::isfinite(c.fx) || !std::isfinite(c.fy) || !std::isfinite(c.cx) ||
        !std::isfinite(c.cy) || c.width != 640 || c.height != 480)
      std::abort();
    if (c.fx < hf::kMinFocalPerPixel * 640 || c.fx > hf::kMaxFocalPerPixel * 640) std::abort();
  } catch (const hf::ParseError& e) {
    hf::fuzz::check_message(e, "camera-intrinsics.txt");
  }
  return 0;
}
