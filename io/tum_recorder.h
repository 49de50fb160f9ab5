// Recording any FrameSource (a live device, above all) as a TUM RGB-D folder that `hashfusion run` replays exactly:
//   DIR/rgb/NNNNNN.png     8-bit RGB, lossless       DIR/rgb.txt     "T rgb/NNNNNN.png" per frame
//   DIR/depth/NNNNNN.png   16-bit, metres * 5000     DIR/depth.txt   "T depth/NNNNNN.png"
//   DIR/camera.json        the source's camera (PinholeCamera::save), so the replay uses the same intrinsics
// with T the frame's time stamp printed "%.6f" (microseconds: OpenNI2 and V4L2 stamps are exact, libcamera's
// nanoseconds are rounded), colour and depth sharing it. Files are numbered, not named by stamp, so equal stamps
// cannot collide; a frame whose stamp does not increase over the previous one is skipped and counted, since a
// TUM list cannot hold one stamp twice. Depth at 5000 units per metre holds millimetre sensors exactly (5 units
// per mm); a 100 um sensor is rounded to 0.2 mm.
//
// The folder appears whole or not at all: frames go into a private folder beside DIR (core/atomic_file.h), which is
// moved into place after the last frame; an existing DIR is refused before the first frame. Recording ends at
// `frames` frames, after `seconds` of wall time, when `stop` is raised (Ctrl-C), or when the source ends (a
// device unplugged: its message is kept); in every case the frames so far are written. Zero frames: nothing is
// written and hf::Error says why.
#pragma once

#include <atomic>
#include <functional>
#include <optional>
#include <string>

#include "io/frame_source.h"

namespace hf {

struct RecordLimits {
  long frames = 0;        // 0 = no frame limit
  double seconds = 0.0;   // 0 = no time limit
  const std::atomic<bool>* stop = nullptr;
  std::function<void(long)> progress;  // frames written so far; may be empty
};

struct RecordResult {
  long frames = 0;             // written
  long skipped = 0;            // bad frames and frames without an increasing stamp
  bool interrupted = false;    // `stop` ended it
  std::string input_ended;     // the source's end message when it ended on its own (device gone)
  std::optional<CaptureStats> capture;
};

// hf::Error "DIR: already exists ..." when DIR exists (a link included); the check record_tum_folder starts with,
// for callers that want it before opening a device.
void check_new_record_folder(const std::string& dir);

// Throws hf::Error naming DIR: it exists, its parent is not writable, a file cannot be written, or no frame came.
RecordResult record_tum_folder(FrameSource& source, const std::string& dir, const RecordLimits& limits = {});

}  // namespace hf
