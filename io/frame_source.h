// FrameSource: the one interface through which the pipeline receives RGB-D frames, whatever the dataset format.
//
// A source yields its frames in time order through next(), which returns
//   ok        a decoded frame (depth in metres, RGB colour, optional ground-truth pose),
//   bad_frame a frame that could not be used (missing/truncated image, wrong size, ...): the caller skips it and
//             prints `message`, a single line naming the file and the problem; reading continues with the next one,
//   end       no more frames (and every later call returns end again).
// A live source (io/live_source.h) also ends with `end` when its device fails or falls silent; `message` then says
// why (a finite source's end has an empty message).
// Problems with the dataset as a whole (missing folder, malformed list file) are reported earlier, by the
// constructor / open_dataset, as hf::Error or hf::ParseError. next() throws only for resource failures
// (std::bad_alloc) that no frame-level skipping can fix.
//
// Thread-safety: next() is called by one thread at a time. The const accessors return data fixed at
// construction, so they may be called from any thread, also while next() runs (PrefetchingSource relies on it).
#pragma once

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/image.h"
#include "core/se3.h"
#include "io/trajectory_io.h"

namespace hf {

struct RgbdFrame {
  size_t index = 0;          // 0-based position in the source, bad frames included (frame k is the k-th next())
  double timestamp_s = 0.0;  // the colour image's time stamp (TUM) or index / frame rate (7-Scenes)
  DepthImage depth;          // metres, 0 = no measurement; same size as `color` and as the source's camera
  ColorImage color;          // RGB
  std::optional<SE3> T_world_camera_gt;  // ground truth where the dataset has one near timestamp_s
  std::string depth_file, color_file;    // full paths, for messages
  // Live sources: when the frame entered the capture queue (the latency of its pose is measured from here).
  std::optional<std::chrono::steady_clock::time_point> arrival;
};

enum class FrameStatus { ok, bad_frame, end };

struct FrameRead {
  FrameStatus status = FrameStatus::end;
  // ok: every field. bad_frame: index, timestamp_s, file names and ground truth (images empty). end: nothing.
  RgbdFrame frame;
  std::string message;  // bad_frame: "FILE: what is wrong" (one line); end of a live source: why; empty otherwise
};

// size() of a source whose length is not known in advance (a live device).
inline constexpr size_t kUnknownFrameCount = size_t(-1);

// What a live source saw between its device and its consumer (io/live_source.h): frames the device delivered,
// frames handed to next(), frames dropped because the consumer was slower, and the two rates over wall time.
struct CaptureStats {
  size_t captured = 0, delivered = 0, dropped = 0;
  std::vector<double> dropped_timestamps_s;  // the dropped frames' time stamps, in capture order
  double input_fps = 0.0;      // captured / seconds from the first to the last captured frame
  double delivered_fps = 0.0;  // delivered / seconds from the first captured to the last delivered frame
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;

  virtual FrameRead next() = 0;

  // The camera all frames are checked against (depth and colour are registered: one camera for both).
  virtual const PinholeCamera& camera() const = 0;
  // Where camera() came from, for reports: e.g. "preset fr1 (folder name 'rgbd_dataset_freiburg1_desk')".
  virtual const std::string& camera_origin() const = 0;
  // Number of frames next() will yield before end (ok and bad ones), known without decoding any image;
  // kUnknownFrameCount for a live device.
  virtual size_t size() const = 0;
  // Short human-readable name: format and folder, e.g. "TUM RGB-D 'data/rgbd_dataset_freiburg1_desk'".
  virtual const std::string& name() const = 0;
  // The dataset's own ground-truth trajectory (T_world_camera with time stamps; empty when it has none), for
  // evaluating estimated trajectories against.
  virtual const Trajectory& ground_truth() const = 0;
  // Frame `index` (0-based, as RgbdFrame::index) read out of order, without moving next()'s cursor; nullopt when
  // the source has no random access (a live device) or `index` >= size(). Const and thread-safe like the accessors:
  // it may run while next() runs on another thread (PrefetchingSource's), for the Python bindings' data[i].
  virtual std::optional<FrameRead> read_at(size_t /*index*/) const { return std::nullopt; }
  // Live sources: the capture counters so far (thread-safe); nullopt for datasets.
  virtual std::optional<CaptureStats> capture_stats() const { return std::nullopt; }
};

}  // namespace hf
