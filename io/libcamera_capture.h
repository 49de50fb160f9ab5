// libcamera cameras (Raspberry Pi cameras, UVC webcams through libcamera's uvcvideo pipeline) as a CaptureDevice
// (io/live_source.h), colour only, through the libcamera C++ API.
//
// `id` empty = the first camera the CameraManager lists. One VideoRecording stream at the requested size in the
// first format of YUYV, BGR888, RGB888, XRGB8888, XBGR8888, NV12, MJPEG the pipeline accepts; four buffers cycle
// through requests. Each completed request's planes are mapped (mmap of their dma-buf), gathered into one buffer
// and decoded by libcamera_planes_to_rgb; depth is empty (all 0) since these cameras have none. Stamps are the
// sensor's (FrameMetadata::timestamp, nanoseconds). grab() waits on a condition variable with its time-out; the
// camera's `disconnected` signal or a failed request is CaptureStatus::failed.
// Failures to open: hf::Error naming the id and the cameras libcamera sees.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/image.h"
#include "io/live_input.h"
#include "io/pixel_formats.h"

namespace hf {

// The io/pixel_formats.h layout of a libcamera (DRM) fourcc, or nullopt when we cannot decode it. DRM names the
// little-endian word, so libcamera's RGB888 is B, G, R in memory (our bgr24) and BGR888 is R, G, B (rgb24).
std::optional<PixelFormat> pixel_format_from_libcamera(std::uint32_t fourcc);

struct PlaneView {
  const std::uint8_t* data = nullptr;
  size_t bytes = 0;
};

// The frame path of the libcamera back-end: the planes of one buffer (in order) decoded to RGB; planes are
// concatenated first, so a two-plane NV12 in separate buffers reads like a contiguous one. Throws hf::Error for
// an unknown fourcc or a short buffer (io/pixel_formats.h).
ColorImage libcamera_planes_to_rgb(std::uint32_t fourcc, const std::vector<PlaneView>& planes, int width, int height,
                                   size_t stride);

std::unique_ptr<CaptureDevice> open_libcamera(const std::string& id, const LiveInputOptions& options);
DeviceListing list_libcamera_devices();

}  // namespace hf
