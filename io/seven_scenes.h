// Microsoft 7-Scenes folder reader: frame-XXXXXX.color.{png,jpg}, frame-XXXXXX.depth.png (16-bit millimetres,
// 0 and 65535 = no measurement), frame-XXXXXX.pose.txt (4x4 row-major camera-to-world = T_world_camera), and an
// optional camera-intrinsics.txt (3x3 K).
//
// Frames are the frame-*.depth.png files, in order of their number N; frame N's stamp is N / frame_rate_hz
// (7-Scenes has no time stamps; it was recorded at 30 Hz). The folder is listed and every pose file parsed at
// construction (a malformed one throws hf::ParseError "FILE:LINE: expected ..."); a frame without a pose file
// has no ground truth. Images are decoded lazily in next(); a missing colour image or any decoding problem is a
// bad_frame. Depth scale: options.depth_scale (0 = 1000).
// Note: 7-Scenes colour and depth come from different, unregistered sensors; the camera is the depth camera's.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/camera.h"
#include "core/se3.h"
#include "io/dataset.h"
#include "io/frame_source.h"

namespace hf {

// A 7-Scenes pose file: 4 lines of 4 numbers, the last line 0 0 0 1 (within 1e-6), a rotation block orthonormal
// within 1e-3 with determinant +1 (re-orthonormalised by SE3::from_matrix), a translation within kMaxCoordinateM
// (1e6 m, io/trajectory_io.h, as the TUM reader). Throws hf::ParseError "FILE:LINE: expected ...".
SE3 parse_seven_scenes_pose(const std::string& text, const std::string& name_for_errors);

// camera-intrinsics.txt: 3 lines of 3 numbers, K = [fx 0 cx; 0 fy cy; 0 0 1] (zeros within 1e-9, K22 = 1 within
// 1e-9, fx, fy > 0, within core/camera.h's check_camera_intrinsics bounds). The file has no image size; the camera
// gets width x height. Throws hf::ParseError.
PinholeCamera parse_seven_scenes_intrinsics(const std::string& text, const std::string& name_for_errors,
                                            int width = 640, int height = 480);

struct SevenScenesFrameInfo {
  int number = 0;  // N of frame-N
  double timestamp_s = 0.0;
  std::string color_file, depth_file;  // full paths; color_file empty when neither .png nor .jpg exists
  std::optional<SE3> T_world_camera_gt;
};

class SevenScenesDataset : public FrameSource {
 public:
  // Throws hf::Error for a missing folder or invalid options, hf::ParseError for malformed pose/intrinsics files.
  explicit SevenScenesDataset(const std::string& folder, const DatasetOptions& options = {});

  FrameRead next() override;
  std::optional<FrameRead> read_at(size_t index) const override {
    if (index >= frames_.size()) return std::nullopt;
    return read(index);
  }
  const PinholeCamera& camera() const override { return camera_.camera; }
  const std::string& camera_origin() const override { return camera_.origin; }
  size_t size() const override { return frames_.size(); }
  const std::string& name() const override { return name_; }
  const Trajectory& ground_truth() const override { return ground_truth_; }

  const std::vector<SevenScenesFrameInfo>& frames() const { return frames_; }
  // Decodes frame i without moving the next() cursor (bad_frame for an image problem or i >= size()).
  FrameRead read(size_t i) const;

 private:
  std::string folder_, name_;
  CameraChoice camera_;
  double depth_scale_;
  Trajectory ground_truth_;
  std::vector<SevenScenesFrameInfo> frames_;
  size_t cursor_ = 0;
};

}  // namespace hf
