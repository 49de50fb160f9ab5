#include "io/seven_scenes.h"

#include <Eigen/Core>
#include <Eigen/LU>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <sstream>

#include "core/bounded_read.h"
#include "core/camera_bounds.h"
#include "core/error.h"
#include "core/number_text.h"
#include "io/trajectory_io.h"

namespace fs = std::filesystem;

namespace hf {
namespace {

// Reads `rows` non-blank lines of exactly `cols` finite numbers each (row-major), nothing else; `row_lines` (when
// given) gets each row's line number, so a value refused later can still be placed in the file.
std::vector<double> parse_number_grid(const std::string& text, const std::string& name, int rows, int cols,
                                      std::vector<int>* row_lines = nullptr) {
  const std::string shape = std::to_string(rows) + " lines of " + std::to_string(cols) + " numbers";
  std::vector<double> values;
  std::istringstream in(text);
  std::string line;
  int lineno = 0, row = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (line.size() > kMaxLineBytes)
      throw ParseError(name, lineno, "expected a line of at most " + std::to_string(kMaxLineBytes) + " bytes, got " +
                                         std::to_string(line.size()));
    std::istringstream ls(line);
    std::string token;
    int n = 0;
    while (ls >> token) {
      if (row == rows) throw ParseError(name, lineno, "expected " + shape + ", got more lines");
      if (n == cols) throw ParseError(name, lineno, "expected " + std::to_string(cols) + " numbers on the line, got more");
      char* end = nullptr;
      const double v = std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0' || !std::isfinite(v))
        throw ParseError(name, lineno, "expected a finite number, got " + quote_for_message(token));
      values.push_back(v);
      ++n;
    }
    if (n == 0) continue;
    if (n != cols)
      throw ParseError(name, lineno, "expected " + std::to_string(cols) + " numbers on the line, got " + std::to_string(n));
    if (row_lines) row_lines->push_back(lineno);
    ++row;
  }
  if (row != rows) throw ParseError(name, 0, "expected " + shape + ", got " + std::to_string(row) + " lines");
  return values;
}

// "frame-000123.depth.png" -> 123 and the digits "000123"; -1 for any other name.
int depth_frame_number(const std::string& filename, std::string& digits) {
  static const std::string prefix = "frame-", suffix = ".depth.png";
  if (filename.size() <= prefix.size() + suffix.size() || filename.compare(0, prefix.size(), prefix) != 0 ||
      filename.compare(filename.size() - suffix.size(), suffix.size(), suffix) != 0)
    return -1;
  digits = filename.substr(prefix.size(), filename.size() - prefix.size() - suffix.size());
  if (digits.empty() || digits.size() > 9 ||
      !std::all_of(digits.begin(), digits.end(), [](unsigned char c) { return std::isdigit(c) != 0; }))
    return -1;
  return std::atoi(digits.c_str());
}

}  // namespace

SE3 parse_seven_scenes_pose(const std::string& text, const std::string& name) {
  std::vector<int> lines;
  const std::vector<double> v = parse_number_grid(text, name, 4, 4, &lines);
  Eigen::Matrix4d T;
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) T(r, c) = v[size_t(r * 4 + c)];
  // The TUM reader's physical bound (io/trajectory_io.h): a camera 1e308 m away is a corrupt file, and its
  // coordinates would overflow every metric and plot range downstream.
  for (int r = 0; r < 3; ++r)
    if (!(std::fabs(T(r, 3)) <= kMaxCoordinateM))
      throw ParseError(name, lines[size_t(r)], "expected a translation within 1e6 m (a physical bound), got " +
                                                   number_for_message(T(r, 3)));
  if ((T.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).cwiseAbs().maxCoeff() > 1e-6)
    throw ParseError(name, lines[3], "expected the last row '0 0 0 1' of a rigid transform");
  const Eigen::Matrix3d R = T.topLeftCorner<3, 3>();
  const double orthonormality_error = (R.transpose() * R - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (!(orthonormality_error <= 1e-3) || !(R.determinant() > 0.0))
    throw ParseError(name, 0, "expected a rotation (orthonormal within 1e-3, determinant +1) in the top-left 3x3");
  return SE3::from_matrix(T);
}

PinholeCamera parse_seven_scenes_intrinsics(const std::string& text, const std::string& name, int width, int height) {
  std::vector<int> lines;
  const std::vector<double> k = parse_number_grid(text, name, 3, 3, &lines);
  if (std::fabs(k[1]) > 1e-9 || std::fabs(k[3]) > 1e-9)
    throw ParseError(name, 0, "expected K without skew ('fx 0 cx / 0 fy cy / 0 0 1')");
  if (std::fabs(k[6]) > 1e-9 || std::fabs(k[7]) > 1e-9 || std::fabs(k[8] - 1.0) > 1e-9)
    throw ParseError(name, 3, "expected the last row of K to be '0 0 1'");
  if (!(k[0] > 0.0) || !(k[4] > 0.0)) throw ParseError(name, 0, "expected positive focal lengths fx and fy");
  if (width < 1 || height < 1) throw ParseError(name, 0, "expected a positive image size");
  PinholeCamera c;
  c.fx = k[0];
  c.cx = k[2];
  c.fy = k[4];
  c.cy = k[5];
  c.width = width;
  c.height = height;
  check_camera_intrinsics(c, name, {{"fx", lines[0]}, {"cx", lines[0]}, {"fy", lines[1]}, {"cy", lines[1]}});
  return c;
}

SevenScenesDataset::SevenScenesDataset(const std::string& folder, const DatasetOptions& options) : folder_(folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw Error(folder + ": 7-Scenes dataset folder not found");
  if (options.depth_scale < 0.0 || !std::isfinite(options.depth_scale))
    throw Error(folder + ": depth scale must be positive (or 0 for the format's 1000)");
  if (!(options.frame_rate_hz > 0.0) || !std::isfinite(options.frame_rate_hz))
    throw Error(folder + ": frame rate must be positive");
  depth_scale_ = options.depth_scale > 0.0 ? options.depth_scale : 1000.0;
  name_ = "7-Scenes '" + folder + "'";
  camera_ = choose_seven_scenes_camera(folder, options.camera);

  struct Found {
    int number;
    std::string digits;
  };
  std::vector<Found> found;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    std::string digits;
    const int n = depth_frame_number(entry.path().filename().string(), digits);
    if (n >= 0) found.push_back({n, digits});
  }
  if (ec) throw Error(folder + ": cannot list the folder (" + ec.message() + ")");
  std::sort(found.begin(), found.end(), [](const Found& a, const Found& b) {
    return a.number != b.number ? a.number < b.number : a.digits < b.digits;
  });

  const fs::path dir(folder);
  for (const Found& f : found) {
    SevenScenesFrameInfo info;
    info.number = f.number;
    info.timestamp_s = f.number / options.frame_rate_hz;
    const std::string stem = "frame-" + f.digits;
    info.depth_file = (dir / (stem + ".depth.png")).string();
    for (const char* ext : {".color.png", ".color.jpg"}) {
      const fs::path p = dir / (stem + ext);
      if (fs::exists(p, ec)) {
        info.color_file = p.string();
        break;
      }
    }
    const fs::path pose_path = dir / (stem + ".pose.txt");
    if (fs::exists(pose_path, ec)) {
      info.T_world_camera_gt = parse_seven_scenes_pose(read_text_file(pose_path.string(), "pose"), pose_path.string());
      ground_truth_.push_back({info.timestamp_s, *info.T_world_camera_gt});
    }
    frames_.push_back(std::move(info));
  }
  // Two names for one number ("frame-1" and "frame-000001") would give equal stamps; keep ground truth sorted
  // strictly as Trajectory users expect by dropping the later duplicates.
  ground_truth_.erase(std::unique(ground_truth_.begin(), ground_truth_.end(),
                                  [](const StampedPose& a, const StampedPose& b) { return a.timestamp_s == b.timestamp_s; }),
                      ground_truth_.end());
}

FrameRead SevenScenesDataset::read(size_t i) const {
  FrameRead r;
  if (i >= frames_.size()) {
    r.status = FrameStatus::bad_frame;
    r.message = name_ + ": frame " + std::to_string(i) + " out of range (" + std::to_string(frames_.size()) + " frames)";
    return r;
  }
  const SevenScenesFrameInfo& info = frames_[i];
  r.frame.index = i;
  r.frame.timestamp_s = info.timestamp_s;
  r.frame.depth_file = info.depth_file;
  r.frame.color_file = info.color_file;
  r.frame.T_world_camera_gt = info.T_world_camera_gt;
  if (info.color_file.empty()) {
    r.status = FrameStatus::bad_frame;
    const std::string stem = info.depth_file.substr(0, info.depth_file.size() - std::string(".depth.png").size());
    r.message = stem + ".color.png: colour image not found (nor .color.jpg)";
    return r;
  }
  r.message = load_frame_images(r.frame, camera_.camera, DepthDecoding{depth_scale_, 65535});
  r.status = r.message.empty() ? FrameStatus::ok : FrameStatus::bad_frame;
  return r;
}

FrameRead SevenScenesDataset::next() {
  if (cursor_ >= frames_.size()) return FrameRead{};
  return read(cursor_++);
}

}  // namespace hf
