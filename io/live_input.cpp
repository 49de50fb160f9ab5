#include "io/live_input.h"

#include <cstdio>

#include "core/error.h"
#include "io/v4l2_capture.h"
#if HF_HAVE_OPENNI2
#include "io/openni2_capture.h"
#endif
#if HF_HAVE_LIBCAMERA
#include "io/libcamera_capture.h"
#endif

namespace hf {
namespace {

bool starts_with(const std::string& s, const std::string& prefix) { return s.rfind(prefix, 0) == 0; }
bool ends_with(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

const char* const kSchemes = "openni2://[URI], FILE.oni, v4l2:///dev/videoN[+/dev/videoM], libcamera://[ID]";

PinholeCamera scaled_to(PinholeCamera c, int width, int height) {
  if (c.width == width && c.height == height) return c;
  const double sx = double(width) / c.width, sy = double(height) / c.height;
  // Pixel centres: x' + 0.5 = (x + 0.5) * s.
  c.fx *= sx;
  c.fy *= sy;
  c.cx = (c.cx + 0.5) * sx - 0.5;
  c.cy = (c.cy + 0.5) * sy - 0.5;
  c.width = width;
  c.height = height;
  return c;
}

}  // namespace

LiveInputOptions live_input_options(const std::string& mode, const std::string& camera) {
  LiveInputOptions o;
  o.camera = camera;
  int w = 0, h = 0, fps = 30, used = 0;
  const bool with_rate = std::sscanf(mode.c_str(), "%dx%d@%d%n", &w, &h, &fps, &used) == 3;
  if (!with_rate) {
    fps = 30;
    used = 0;
    if (std::sscanf(mode.c_str(), "%dx%d%n", &w, &h, &used) != 2) used = -1;
  }
  if (used != int(mode.size()) || w < 16 || h < 16 || w > 8192 || h > 8192 || fps < 1 || fps > 1000)
    throw Error("--live-mode '" + mode + "': expected WIDTHxHEIGHT@FPS, e.g. 640x480@30");
  o.width = w;
  o.height = h;
  o.fps = fps;
  return o;
}

bool is_live_input(const std::string& input) {
  return starts_with(input, "openni2://") || starts_with(input, "v4l2://") || starts_with(input, "libcamera://") ||
         ends_with(input, ".oni");
}

CameraChoice choose_live_camera(const std::string& option, const std::optional<PinholeCamera>& device_camera,
                                const std::string& device_camera_origin, int width, int height) {
  CameraChoice c;
  if (!option.empty()) {
    c = camera_from_option(option);
  } else if (device_camera) {
    c = {*device_camera, device_camera_origin};
  } else {
    c = {PinholeCamera::preset("ros"), "preset ros (the device reports no intrinsics; give --camera FILE for a "
                                       "calibration)"};
  }
  if (c.camera.width != width || c.camera.height != height) {
    c.origin += ", scaled from " + std::to_string(c.camera.width) + "x" + std::to_string(c.camera.height);
    c.camera = scaled_to(c.camera, width, height);
  }
  return c;
}

std::unique_ptr<FrameSource> open_live_input(const std::string& input, const LiveInputOptions& options) {
  std::unique_ptr<CaptureDevice> device;
  LiveOptions live = options.live;
  if (starts_with(input, "openni2://") || ends_with(input, ".oni")) {
#if HF_HAVE_OPENNI2
    const bool file = !starts_with(input, "openni2://");
    device = open_openni2(file ? input : input.substr(10), options);
    if (file) live.drop_when_full = false;  // a recording keeps every frame it has
#else
    throw Error(input + ": OpenNI2 support is not built in (install libopenni2-dev and reconfigure)");
#endif
  } else if (starts_with(input, "v4l2://")) {
    device = open_v4l2(parse_v4l2_nodes(input.substr(7)), options);
  } else if (starts_with(input, "libcamera://")) {
#if HF_HAVE_LIBCAMERA
    device = open_libcamera(input.substr(12), options);
#else
    throw Error(input + ": libcamera support is not built in (install libcamera-dev and reconfigure)");
#endif
  } else {
    throw Error(input + ": not a live input; live inputs are " + kSchemes);
  }
  return std::make_unique<LiveSource>(std::move(device), live);
}

std::vector<DeviceListing> list_devices() {
  std::vector<DeviceListing> all;
  auto guarded = [&](const char* backend, auto&& list) {
    try {
      all.push_back(list());
    } catch (const std::exception& e) {
      DeviceListing l;
      l.backend = backend;
      l.note = e.what();
      all.push_back(l);
    }
  };
#if HF_HAVE_OPENNI2
  guarded("openni2", [] { return list_openni2_devices(); });
#else
  all.push_back({"openni2", false, "not built in (libopenni2-dev missing at configure time)", {}});
#endif
  guarded("v4l2", [] { return list_v4l2_devices(); });
#if HF_HAVE_LIBCAMERA
  guarded("libcamera", [] { return list_libcamera_devices(); });
#else
  all.push_back({"libcamera", false, "not built in (libcamera-dev missing at configure time)", {}});
#endif
  return all;
}

}  // namespace hf
