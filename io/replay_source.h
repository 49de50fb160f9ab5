// A recording replayed at its recorded rate through a live source's queue (io/live_source.h): what a live user of
// the same sensor would get from the same scene (`hashfusion run --realtime`).
//
//   auto source = open_realtime_replay(open_dataset(dir));   // frames arrive at their time stamps
//   while (...) source->next();                             // the freshest of at most two queued frames
//
// The recording is read on the live source's capture thread, and each frame is queued when the steady clock
// reaches its time stamp (relative to the first frame's; 7-Scenes, which has none, at its reader's 30 Hz). The
// queue is LiveSource's: LiveOptions::queue_frames (2) with the oldest frame dropped when the consumer is behind,
// counted in capture_stats() with the dropped frames' time stamps. Frames carry their ground truth and their
// arrival time (RgbdFrame::arrival). A recording frame that is unreadable is skipped (a camera would not have
// delivered it). Decoding a frame takes the capture thread's time, as a driver's would: when it is slower than the
// recorded rate, frames arrive late rather than being skipped, and the input fps says so.
// Thread-safety: as LiveSource; ground_truth() and the accessors are the recording's, fixed at construction.
#pragma once

#include <memory>

#include "io/frame_source.h"
#include "io/live_source.h"

namespace hf {

struct ReplayOptions {
  double speed = 1.0;  // 1 = the recorded rate; 2 = twice as fast (> 0)
  LiveOptions live;    // the queue (2 frames, drop-oldest) and time-outs, as for a camera
};

// Throws hf::Error for a null recording or a non-positive speed. The recording is read from the first next() on.
std::unique_ptr<FrameSource> open_realtime_replay(std::unique_ptr<FrameSource> recording,
                                                  const ReplayOptions& options = {});

}  // namespace hf
