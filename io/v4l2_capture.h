// V4L2 video nodes as a CaptureDevice (io/live_source.h): memory-mapped streaming I/O on /dev/videoN.
//
// `nodes`: one node (colour, or Z16 depth) or two (one colour, one depth, in either order; paired by their buffer
// time stamps with io/frame_pairing.h). The colour format is the first the node offers of YUYV, UYVY, RGB24,
// BGR24, MJPEG, NV12 at the requested size (io/pixel_formats.h decodes them); depth is Z16 times z16_unit_m. A
// colour-only node gives frames with empty depth (all 0: no measurement), a depth-only node black colour.
// grab() waits in poll() with its time-out; ENODEV or POLLERR (the device unplugged) is CaptureStatus::failed.
// Camera: choose_live_camera (V4L2 reports no intrinsics).
// Failures to open: hf::Error with one line naming the node: missing node (and the nodes that exist), not a
// capture device, no supported format at the size (and the formats it has), streaming refused.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "io/live_input.h"

namespace hf {

// Splits "v4l2:///dev/video0+/dev/video2" (scheme already removed: "/dev/video0+/dev/video2") into node paths.
std::vector<std::string> parse_v4l2_nodes(const std::string& spec);

std::unique_ptr<CaptureDevice> open_v4l2(const std::vector<std::string>& nodes, const LiveInputOptions& options);
DeviceListing list_v4l2_devices();

}  // namespace hf
