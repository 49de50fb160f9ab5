#include "io/tum_dataset.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <sstream>

#include "core/bounded_read.h"
#include "core/error.h"
#include "io/associate.h"

namespace fs = std::filesystem;

namespace hf {
namespace {

bool parse_double(const std::string& token, double& value) {
  char* end = nullptr;
  value = std::strtod(token.c_str(), &end);
  return end != token.c_str() && *end == '\0' && std::isfinite(value);
}

}  // namespace

std::vector<TumListEntry> parse_tum_list(const std::string& text, const std::string& name) {
  std::vector<TumListEntry> entries;
  std::istringstream in(text);
  std::string line;
  int lineno = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.size() > kMaxLineBytes)
      throw ParseError(name, lineno, "expected a line of at most " + std::to_string(kMaxLineBytes) + " bytes, got " +
                                         std::to_string(line.size()));
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const size_t first = line.find_first_not_of(" \t\r\v\f");
    if (first == std::string::npos || line[first] == '#') continue;
    // associate.py also accepts commas between fields.
    std::string fields_text = line;
    std::replace(fields_text.begin(), fields_text.end(), ',', ' ');
    std::istringstream ls(fields_text);
    std::vector<std::string> fields;
    std::string token;
    while (fields.size() < 3 && ls >> token) fields.push_back(token);
    if (fields.size() != 2)
      throw ParseError(name, lineno, "expected 'timestamp filename', got " + quote_for_message(line));
    double t = 0.0;
    if (!parse_double(fields[0], t))
      throw ParseError(name, lineno, "expected a finite time stamp in seconds, got " + quote_for_message(fields[0]));
    if (entries.size() == kMaxTumListEntries)
      throw ParseError(name, lineno, "expected at most " + std::to_string(kMaxTumListEntries) +
                                         " entries (the list limit), got more");
    entries.push_back({t, fields[1], lineno});
  }
  std::stable_sort(entries.begin(), entries.end(),
                   [](const TumListEntry& a, const TumListEntry& b) { return a.timestamp_s < b.timestamp_s; });
  for (size_t i = 1; i < entries.size(); ++i) {
    if (entries[i].timestamp_s == entries[i - 1].timestamp_s) {
      const TumListEntry& later = entries[i].line > entries[i - 1].line ? entries[i] : entries[i - 1];
      const TumListEntry& earlier = entries[i].line > entries[i - 1].line ? entries[i - 1] : entries[i];
      throw ParseError(name, later.line,
                       "expected each time stamp once, got the stamp of line " + std::to_string(earlier.line) + " again");
    }
  }
  return entries;
}

std::vector<TumListEntry> read_tum_list(const std::string& path) {
  return parse_tum_list(read_text_file(path, "image list"), path);
}

double nearest_sample_distance(const Trajectory& trajectory, double t) {
  if (trajectory.empty()) return std::numeric_limits<double>::infinity();
  auto it = std::lower_bound(trajectory.begin(), trajectory.end(), t,
                             [](const StampedPose& p, double s) { return p.timestamp_s < s; });
  double best = std::numeric_limits<double>::infinity();
  if (it != trajectory.end()) best = std::fabs(it->timestamp_s - t);
  if (it != trajectory.begin()) best = std::min(best, std::fabs(t - std::prev(it)->timestamp_s));
  return best;
}

std::optional<SE3> interpolate_pose(const Trajectory& trajectory, double t, double max_difference_s) {
  if (trajectory.empty() || !std::isfinite(t)) return std::nullopt;
  // First sample strictly after t; the one before it (if any) is at or before t.
  auto after = std::upper_bound(trajectory.begin(), trajectory.end(), t,
                                [](double s, const StampedPose& p) { return s < p.timestamp_s; });
  if (after == trajectory.begin()) {
    if (after->timestamp_s - t <= max_difference_s) return after->T_world_camera;
    return std::nullopt;
  }
  const StampedPose& a = *std::prev(after);
  if (after == trajectory.end()) {
    if (t - a.timestamp_s <= max_difference_s) return a.T_world_camera;
    return std::nullopt;
  }
  const StampedPose& b = *after;
  if (std::min(t - a.timestamp_s, b.timestamp_s - t) > max_difference_s) return std::nullopt;
  const double span = b.timestamp_s - a.timestamp_s;
  const double alpha = span > 0.0 ? (t - a.timestamp_s) / span : 0.0;
  return SE3::interpolate(a.T_world_camera, b.T_world_camera, alpha);
}

TumDataset::TumDataset(const std::string& folder, const DatasetOptions& options) : folder_(folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw Error(folder + ": TUM RGB-D dataset folder not found");
  if (options.depth_scale < 0.0 || !std::isfinite(options.depth_scale))
    throw Error(folder + ": depth scale must be positive (or 0 for the format's 5000)");
  if (!(options.association.max_difference_s > 0.0) || !std::isfinite(options.association.offset_s))
    throw Error(folder + ": association needs a positive max difference and a finite offset");
  if (!(options.gt_max_difference_s >= 0.0))
    throw Error(folder + ": ground-truth max difference must not be negative");
  depth_scale_ = options.depth_scale > 0.0 ? options.depth_scale : 5000.0;
  name_ = "TUM RGB-D '" + folder + "'";

  const fs::path dir(folder);
  const std::vector<TumListEntry> rgb = read_tum_list((dir / "rgb.txt").string());
  const std::vector<TumListEntry> depth = read_tum_list((dir / "depth.txt").string());
  const fs::path gt_path = dir / "groundtruth.txt";
  // Absent: no ground truth. Present in any other form (a link loop, a dangling link, no permission to look):
  // an error naming it, not a run silently without ground truth (issue 35's leftover).
  std::error_code gt_ec;
  const bool gt_exists = fs::exists(gt_path, gt_ec);
  const bool gt_is_link = fs::is_symlink(fs::symlink_status(gt_path, ec));
  if (gt_ec || (gt_is_link && !gt_exists))
    throw Error(gt_path.string() + ": cannot read the ground truth (" +
                (gt_ec ? gt_ec.message() : std::string("a link to nothing")) + ")");
  if (gt_exists) ground_truth_ = read_tum_trajectory(gt_path.string());
  camera_ = choose_tum_camera(folder, options.camera);

  std::vector<double> rgb_stamps, depth_stamps;
  for (const TumListEntry& e : rgb) rgb_stamps.push_back(e.timestamp_s);
  for (const TumListEntry& e : depth) depth_stamps.push_back(e.timestamp_s);
  const std::vector<Match> matches = associate(rgb_stamps, depth_stamps, options.association);

  summary_.rgb_entries = rgb.size();
  summary_.depth_entries = depth.size();
  summary_.groundtruth_poses = ground_truth_.size();
  frames_.reserve(matches.size());
  for (const Match& m : matches) {
    TumFrameInfo f;
    f.timestamp_s = rgb[m.a].timestamp_s;
    f.depth_timestamp_s = depth[m.b].timestamp_s;
    f.color_file = (dir / rgb[m.a].file).string();
    f.depth_file = (dir / depth[m.b].file).string();
    f.T_world_camera_gt = interpolate_pose(ground_truth_, f.timestamp_s, options.gt_max_difference_s);
    summary_.max_rgb_depth_difference_s =
        std::max(summary_.max_rgb_depth_difference_s,
                 std::fabs(f.timestamp_s - (f.depth_timestamp_s + options.association.offset_s)));
    if (f.T_world_camera_gt) {
      ++summary_.frames_with_gt;
      summary_.max_gt_distance_s =
          std::max(summary_.max_gt_distance_s, nearest_sample_distance(ground_truth_, f.timestamp_s));
    }
    frames_.push_back(std::move(f));
  }
  summary_.frames = frames_.size();
}

FrameRead TumDataset::read(size_t i) const {
  FrameRead r;
  if (i >= frames_.size()) {
    r.status = FrameStatus::bad_frame;
    r.message = name_ + ": frame " + std::to_string(i) + " out of range (" + std::to_string(frames_.size()) + " frames)";
    return r;
  }
  const TumFrameInfo& info = frames_[i];
  r.frame.index = i;
  r.frame.timestamp_s = info.timestamp_s;
  r.frame.color_file = info.color_file;
  r.frame.depth_file = info.depth_file;
  r.frame.T_world_camera_gt = info.T_world_camera_gt;
  r.message = load_frame_images(r.frame, camera_.camera, DepthDecoding{depth_scale_, -1});
  r.status = r.message.empty() ? FrameStatus::ok : FrameStatus::bad_frame;
  return r;
}

FrameRead TumDataset::next() {
  if (cursor_ >= frames_.size()) return FrameRead{};
  return read(cursor_++);
}

}  // namespace hf
