// OpenNI2 devices and .oni recordings as a CaptureDevice (io/live_source.h), through the OpenNI2 C++ API.
//
// Opening: `uri` empty = the first device OpenNI2 enumerates; a path ending in .oni = OpenNI2's file driver (the
// file must exist). Depth (DEPTH_1_MM or DEPTH_100_UM) and colour (RGB888, YUV422, YUYV, JPEG) streams of the
// requested size, the nearest rate; depth registered to colour by the device where it supports it
// (IMAGE_REGISTRATION_DEPTH_TO_COLOR), mirroring off where the stream has the property, depth/colour frame sync
// on where the device has it. A recording keeps its recorded modes and plays at its recorded rate.
// Pairing: each stream's newest frame is held; a depth and a colour frame whose device stamps (microseconds)
// differ by at most max_pair_difference_s make a frame, stamped with the colour stamp; an older unpaired frame is
// replaced by its stream's next one.
// Intrinsics: from the colour stream's fields of view when the device reports them (fx = w / (2 tan(hfov / 2))),
// else as choose_live_camera says.
// grab() waits in OpenNI::waitForAnyStream with its time-out; a disconnected device (OpenNI2's disconnect event)
// or a failing read is CaptureStatus::failed; a recording ends after its last depth frame.
// Failures to open: hf::Error with one line naming the URI and what OpenNI2 sees.
// Thread-safety: one thread calls grab() (LiveSource's); OpenNI2 is initialised once per process per instance.
#pragma once

#include <memory>
#include <string>

#include "io/live_input.h"

namespace hf {

std::unique_ptr<CaptureDevice> open_openni2(const std::string& uri, const LiveInputOptions& options);
DeviceListing list_openni2_devices();

}  // namespace hf
