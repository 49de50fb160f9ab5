// Live inputs by name: the `--input` forms of live capture, the back-ends that serve them, and device listing.
//
//   openni2://            the first OpenNI2 device (Kinect, Xtion, Carmine, Astra ...)
//   openni2://URI         the OpenNI2 device of that URI (as `hashfusion devices` prints it)
//   FILE.oni              an OpenNI2 recording, played by OpenNI2's own file driver at its recorded rate
//   v4l2:///dev/videoN    a V4L2 node: colour (YUYV, UYVY, MJPEG, RGB24, ...) or depth (Z16, RealSense UVC)
//   v4l2:///dev/videoA+/dev/videoB   two nodes paired by time stamp: one colour, one depth, in either order
//   libcamera://ID        the libcamera camera of that id; libcamera:// the first
// Each opens into a LiveSource (io/live_source.h): a capture thread, a bounded queue that drops the oldest frame
// when processing is slower (a .oni file waits instead: every recorded frame is kept), time-outs on every wait.
// A colour-only device (a webcam, a Pi camera) gives frames without depth: the pipeline counts them lost, and
// `record` still writes them.
//
// Camera: `camera` (a preset name or a camera file, io/dataset.h camera_from_option) when given; else the device's
// own intrinsics when it reports them (OpenNI2 fields of view); else the "ros" preset (525 px at 640x480, the
// Kinect-class default); presets are scaled to the stream's resolution. camera_origin() says which.
// Failures: hf::Error with one line naming what was asked and what exists ("openni2://foo: no such device; OpenNI2
// sees: none"), for an unknown scheme, an absent device, a back-end not built in, an unsupported mode.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/frame_source.h"
#include "io/live_source.h"

namespace hf {

struct LiveInputOptions {
  std::string camera;           // "--camera PRESET|FILE"; empty = the device's, else the ros preset
  int width = 640, height = 480;  // requested resolution (a device without it is refused, naming its modes)
  int fps = 30;                 // requested rate; the nearest mode at the resolution is taken
  // Depth and colour frames whose stamps differ by more than this are not paired; half a 30 Hz period.
  double max_pair_difference_s = 1.0 / 60.0;
  // Raw Z16 units per metre of a V4L2 depth node (RealSense: 1 mm).
  double z16_unit_m = 0.001;
  LiveOptions live;             // queue and time-outs
};

// Options from the command line: `mode` "WIDTHxHEIGHT@FPS" (or "WIDTHxHEIGHT"), `camera` as LiveInputOptions.
// Throws hf::Error "--live-mode 'X': expected WIDTHxHEIGHT@FPS" for anything else or sizes outside 16..8192, rates
// outside 1..1000.
LiveInputOptions live_input_options(const std::string& mode, const std::string& camera);

// True when `input` names a live form above (by scheme, or a .oni file name); says nothing of its existence.
bool is_live_input(const std::string& input);

// Opens the input. Throws hf::Error (see above).
std::unique_ptr<FrameSource> open_live_input(const std::string& input, const LiveInputOptions& options = {});

struct DeviceListing {
  std::string backend;               // "openni2", "v4l2", "libcamera"
  bool available = true;             // false: not built in (the reason is in `note`)
  std::string note;                  // e.g. "none connected", "not built in: libcamera headers missing"
  std::vector<std::string> devices;  // "URI  name: modes ..." one line each
};

// What each back-end sees now. Never throws: a back-end failure becomes its note.
std::vector<DeviceListing> list_devices();

// The camera for a stream of width x height: `option` when non-empty, else `device_camera` when present, else
// the ros preset; presets and files of another size are scaled to it. `origin` says which.
CameraChoice choose_live_camera(const std::string& option, const std::optional<PinholeCamera>& device_camera,
                                const std::string& device_camera_origin, int width, int height);

}  // namespace hf
