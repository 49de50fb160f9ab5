// Opening a dataset folder: options shared by the readers, choosing the camera, and format auto-detection.
//
// Camera choice (TUM RGB-D and generic folders), first that applies:
//   1. options.camera: a preset name (PinholeCamera::preset_names()) or the path of a camera file;
//   2. camera.json, else camera.txt, inside the folder (PinholeCamera::load format);
//   3. the TUM camera the folder's name identifies: "freiburg1" or "fr1" as a separate word (delimited by
//      non-alphanumerics, case-insensitive), likewise fr2 and fr3. fr3 -> the fr3 preset; fr1 -> "fr1-registered"
//      and fr2 -> "ros": their images are distorted and the depth is pre-registered to them, which TUM recommends
//      reading as a pinhole (the ROS defaults) rather than undistorting; for fr1 the pinhole that tracks its
//      recordings best is measured (see io/dataset.cpp);
//   4. the "ros" preset (525, 525, 319.5, 239.5).
// 7-Scenes: options.camera, else camera-intrinsics.txt in the folder (3x3 K, size 640x480), else "7scenes".
// The choice and the reason are kept as CameraChoice::origin, a string the reports print.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include "core/camera.h"
#include "io/associate.h"
#include "io/frame_source.h"
#include "io/image_io.h"

namespace hf {

struct DatasetOptions {
  std::string camera;  // "--camera PRESET|FILE"; empty = choose automatically (see above)
  // Raw 16-bit depth units per metre; 0 = the format's own (TUM 5000, 7-Scenes 1000 i.e. millimetres).
  double depth_scale = 0.0;
  // TUM colour-to-depth association (associate.py's --max_difference and --offset; offset is added to depth
  // stamps).
  AssociationOptions association{};
  // A frame's ground-truth pose is interpolated between the bracketing samples when one of them lies within
  // this many seconds of the frame's stamp, and absent otherwise.
  double gt_max_difference_s = 0.02;
  // 7-Scenes has no time stamps: frame k gets k / frame_rate_hz seconds.
  double frame_rate_hz = 30.0;
  // open_dataset wraps the reader in a PrefetchingSource holding up to this many decoded frames; 0 = none
  // (decode on the caller's thread).
  size_t prefetch_frames = 4;
};

struct CameraChoice {
  PinholeCamera camera;
  std::string origin;  // e.g. "camera file '/data/x/camera.json'", "preset fr1 (folder name 'rgbd_..._freiburg1_desk')"
};

enum class DatasetFormat { tum, seven_scenes, unknown };

// Resolves options.camera alone: a preset name, else an existing camera file. Throws hf::Error when it is
// neither (naming the known presets), hf::ParseError for a malformed file. Requires a non-empty `camera_option`.
CameraChoice camera_from_option(const std::string& camera_option);

// The preset a folder name identifies ("fr1", "fr2", "fr3"), or "" when none; only the last path component is
// examined ("a/rgbd_dataset_freiburg2_xyz/" -> "fr2").
std::string preset_from_folder_name(const std::string& folder);

// The camera for a TUM-style folder (rules 1-4 above).
CameraChoice choose_tum_camera(const std::string& folder, const std::string& camera_option);
// The camera for a 7-Scenes folder.
CameraChoice choose_seven_scenes_camera(const std::string& folder, const std::string& camera_option);

// TUM when the folder has rgb.txt or depth.txt, 7-Scenes when it has a frame-*.depth.png, else unknown. Does not
// throw (a missing folder is unknown).
DatasetFormat detect_dataset_format(const std::string& folder);

// Decodes frame.depth_file and frame.color_file into frame.depth / frame.color and checks that both have the
// camera's size. Returns "" on success, else the bad_frame message (one line naming the file; the images are then
// cleared). Never throws hf::Error.
std::string load_frame_images(RgbdFrame& frame, const PinholeCamera& camera, const DepthDecoding& decoding);

// Reads a whole text file: only a regular file of at most kMaxTextFileBytes (core/bounded_read.h), so a FIFO cannot
// block and a link to /dev/zero cannot exhaust memory; hf::Error "PATH: cannot read WHAT: ..." otherwise.
std::string read_text_file(const std::string& path, const std::string& what);

// Opens the dataset at `path` (a folder) with the detected reader, wrapped in a PrefetchingSource unless
// options.prefetch_frames is 0. Throws hf::Error naming the path for a missing folder, an unknown layout or a
// dataset with no frames, and the reader's hf::Error / hf::ParseError for malformed files. The returned source
// owns its prefetch thread (joined on destruction).
std::unique_ptr<FrameSource> open_dataset(const std::string& path, const DatasetOptions& options = {});

}  // namespace hf
