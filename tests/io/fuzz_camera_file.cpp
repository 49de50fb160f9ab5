// Fuzzes hf::PinholeCamera::parse (camera.json / camera.txt): a parsed camera is always valid (finite, positive
// focal lengths, size, focal lengths and principal point within the documented limits); every failure is an
// hf::ParseError with a short printable
// message.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "core/camera.h"
#include "core/camera_bounds.h"
#include "core/error.h"
#include "tests/io/fuzz_message_check.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const hf::PinholeCamera c = hf::PinholeCamera::parse(text, "camera.json");
    if (!(c.fx > 0.0) || !(c.fy > 0.0) || !std::isfinite(c.fx) || !std::isfinite(c.fy) || !std::isfinite(c.cx) ||
        !std::isfinite(c.cy) || c.width < 1 || c.height < 1 || c.width > 16384 || c.height > 16384)
      std::abort();
    // Issue 35: the physical bounds (fields of view 0.5..170 degrees, principal point near the image).
    if (c.fx < hf::kMinFocalPerPixel * c.width || c.fx > hf::kMaxFocalPerPixel * c.width ||
        c.fy < hf::kMinFocalPerPixel * c.height || c.fy > hf::kMaxFocalPerPixel * c.height || c.cx < -c.width ||
        c.cx > 2.0 * c.width || c.cy < -c.height || c.cy > 2.0 * c.height)
      std::abort();
  } catch (const hf::ParseError& e) {
    if (e.file() != "camera.json") std::abort();
    hf::fuzz::check_message(e, "camera.json");
  }
  return 0;
}
