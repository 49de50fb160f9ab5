// TUM RGB-D folder reader: rgb.txt, depth.txt, optional groundtruth.txt, rgb/ and depth/ PNGs.
//
// List files ("timestamp filename" per line, '#' comments, blank lines, any whitespace between fields) are parsed
// completely at construction; a malformed line throws hf::ParseError "FILE:LINE: expected ...". Colour and depth
// are associated exactly as TUM's associate.py (io/associate.h) with options.association. Each frame takes the
// colour image's stamp; its ground-truth pose is SE3::interpolate between the groundtruth.txt samples that
// bracket the stamp, present only when one of them lies within options.gt_max_difference_s (at the ends of the
// ground truth the nearest sample is used as is, never extrapolated). A missing groundtruth.txt means no ground
// truth. Depth PNGs are 16-bit, divided by options.depth_scale (0 = 5000).
//
// Images are decoded lazily in next(); failures there are bad_frame results, never exceptions.
// Thread-safety: as FrameSource.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/dataset.h"
#include "io/frame_source.h"
#include "io/trajectory_io.h"

namespace hf {

struct TumListEntry {
  double timestamp_s = 0.0;
  std::string file;  // as written in the list, relative to the dataset folder
  int line = 0;      // 1-based line in the list file, for messages
};

// At most this many entries in one list (9 hours at 30 Hz); more is refused naming the limit.
inline constexpr size_t kMaxTumListEntries = 1'000'000;

// Parses an rgb.txt / depth.txt text. Entries come back sorted by time (stable). Throws hf::ParseError
// "NAME:LINE: expected 'timestamp filename', got '...'" for a line without exactly two fields, a non-finite or
// non-numeric time stamp, a time stamp listed twice, a line longer than kMaxLineBytes (core/bounded_read.h) or more
// than kMaxTumListEntries entries. Input is quoted with quote_for_message (short, printable).
std::vector<TumListEntry> parse_tum_list(const std::string& text, const std::string& name_for_errors);
// hf::Error when the file cannot be read or is not a regular file (read_text_file, io/dataset.h).
std::vector<TumListEntry> read_tum_list(const std::string& path);

// Ground truth at time t: interpolated between the samples bracketing t when one of them is within
// max_difference_s of t; the single nearest sample when t lies outside the trajectory's span but within
// max_difference_s of its end; nullopt otherwise. `trajectory` must be sorted by time (parse_tum_trajectory
// guarantees it).
std::optional<SE3> interpolate_pose(const Trajectory& trajectory, double t, double max_difference_s);

// Distance in seconds from t to the nearest sample (infinity for an empty trajectory).
double nearest_sample_distance(const Trajectory& trajectory, double t);

struct TumFrameInfo {
  double timestamp_s = 0.0;        // colour stamp
  double depth_timestamp_s = 0.0;  // stamp of the associated depth image (before the offset)
  std::string color_file, depth_file;  // full paths
  std::optional<SE3> T_world_camera_gt;
};

// Association statistics, for reports and tests.
struct TumSummary {
  size_t rgb_entries = 0, depth_entries = 0, groundtruth_poses = 0;
  size_t frames = 0;                   // associated colour/depth pairs
  size_t frames_with_gt = 0;
  double max_rgb_depth_difference_s = 0.0;  // over frames, |t_rgb - (t_depth + offset)|
  double max_gt_distance_s = 0.0;           // over frames with ground truth, distance to the nearest GT sample
};

class TumDataset : public FrameSource {
 public:
  // Reads and associates the lists. Throws hf::Error for a missing folder, rgb.txt or depth.txt,
  // hf::ParseError for malformed lists or groundtruth.txt, hf::Error for an invalid camera option.
  explicit TumDataset(const std::string& folder, const DatasetOptions& options = {});

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

  const std::vector<TumFrameInfo>& frames() const { return frames_; }
  const TumSummary& summary() const { return summary_; }
  // Decodes frame i without moving the next() cursor (bad_frame for an image problem or i >= size()).
  FrameRead read(size_t i) const;

 private:
  std::string folder_, name_;
  CameraChoice camera_;
  double depth_scale_;
  Trajectory ground_truth_;
  std::vector<TumFrameInfo> frames_;
  TumSummary summary_;
  size_t cursor_ = 0;
};

}  // namespace hf
