// Writing a synthetic sequence as a TUM RGB-D folder:
//   DIR/rgb/T.png     8-bit RGB          DIR/rgb.txt          "# ..." header, then "T rgb/T.png" lines
//   DIR/depth/T.png   16-bit, metres*5000  DIR/depth.txt        "T depth/T.png"
//   DIR/groundtruth.txt  "T tx ty tz qx qy qz qw" (T_world_camera, io/trajectory_io.h)
//   DIR/camera.json   PinholeCamera::save
// with T the time stamp printed with 6 decimals (frame i at i / 30 s). Colour and depth share stamps.
//
// The folder appears whole or not at all: everything is written into a fresh private folder beside DIR
// (core/atomic_file.h make_private_folder_beside: ".DIR.XXXXXX", so nothing of anyone else's is touched), which
// replaces DIR at the end in one exchange; on any failure or exception from `progress` it is removed and DIR is
// untouched. Replacing (overwrite) is refused for the root, the working folder or one above it, a home folder, a
// link, and any folder that does not look like a previous output (only the entries listed above, PNGs in rgb/ and
// depth/).
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

// Throws hf::Error naming the path: DIR exists (without overwrite) or may not be replaced (above), its parent cannot
// be written, a file cannot be written, or the final exchange fails.
void write_tum_folder(const SyntheticSequence& sequence, const std::string& dir, const TumWriteOptions& options = {});

// The same folder from any in-process sequence (a mesh orbit, datasets/mesh_orbit.h): `frames` frames rendered by
// frame(i) (colour, depth, time stamp, T_world_camera), seen by `camera`; the names go into the lists' and
// groundtruth.txt's headers.
struct TumSequence {
  int frames = 0;
  PinholeCamera camera;
  std::string list_name;        // "# file: '...'" of rgb.txt and depth.txt
  std::string trajectory_name;  // "ground truth trajectory (T_world_camera) of ..." of groundtruth.txt
  std::function<double(int)> timestamp_s;
  std::function<SyntheticFrame(int)> frame;
};
void write_tum_folder(const TumSequence& sequence, const std::string& dir, const TumWriteOptions& options = {});

// "%.6f" of a time stamp, the TUM file-name and list format.
std::string tum_stamp(double timestamp_s);

}  // namespace hf::datasets
