// Writing a synthetic sequence as a TUM RGB-D folder:
//   DIR/rgb/T.png     8-bit RGB          DIR/rgb.txt          "# ..." header, then "T rgb/T.png" lines
//   DIR/depth/T.png   16-bit, metres*5000  DIR/depth.txt        "T depth/T.png"
//   DIR/groundtruth.txt  "T tx ty tz qx qy qz qw" (T_world_camera, io/trajectory_io.h)
//   DIR/camera.json   PinholeCamera::save
// with T the time stamp printed with 6 decimals (frame i at i / 30 s). Colour and depth share stamps.
//
// The folder appears whole or not at all: everything is written into "DIR.tmp" (removed first if a previous run
// left it behind), which is renamed to DIR at the end; on any failure DIR.tmp is removed and DIR is untouched.
#pragma once

#include <functional>
#include <string>

#include "datasets/synthetic_sequence.h"

namespace hf::datasets {

struct TumWriteOptions {
  bool overwrite = false;  // replace an existing DIR; otherwise an existing DIR is an error
  // Called after each frame with (frames written, total); may be empty.
  std::function<void(int, int)> progress;
};

// Throws hf::Error naming the path: DIR exists (without overwrite), its parent cannot be written, a file cannot be
// written, or the final rename fails.
void write_tum_folder(const SyntheticSequence& sequence, const std::string& dir, const TumWriteOptions& options = {});

// "%.6f" of a time stamp, the TUM file-name and list format.
std::string tum_stamp(double timestamp_s);

}  // namespace hf::datasets
