#include "datasets/tum_writer.h"

#include <cstdio>
#include <filesystem>
#include <ostream>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/image_io.h"
#include "io/trajectory_io.h"

namespace hf::datasets {

namespace fs = std::filesystem;

std::string tum_stamp(double t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", t);
  return buf;
}

namespace {

void write_list(const std::string& path, const std::string& what, const std::string& sub,
                const SyntheticSequence& seq) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# " << what << " images\n# file: 'synthetic " << seq.options().preset << " seed "
        << seq.options().seed << "'\n# timestamp filename\n";
    for (int i = 0; i < seq.size(); ++i) {
      const std::string t = tum_stamp(seq.timestamp_s(i));
      out << t << ' ' << sub << '/' << t << ".png\n";
    }
  });
}

}  // namespace

void write_tum_folder(const SyntheticSequence& seq, const std::string& dir_in, const TumWriteOptions& options) {
  if (dir_in.empty()) throw Error("generate: expected a non-empty output folder");
  std::string dir = dir_in;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  std::error_code ec;
  const bool exists = fs::exists(dir, ec);
  if (exists && !options.overwrite) throw Error(dir + ": already exists (choose another folder or overwrite it)");
  if (exists && !fs::is_directory(dir, ec)) throw Error(dir + ": exists and is not a folder");
  const std::string tmp = dir + ".tmp";
  if (fs::exists(fs::symlink_status(tmp, ec))) {
    fs::remove_all(tmp, ec);
    if (ec) throw Error(tmp + ": cannot remove the leftover temporary folder (" + ec.message() + ")");
  }
  fs::create_directories(fs::path(tmp) / "rgb", ec);
  if (!ec) fs::create_directories(fs::path(tmp) / "depth", ec);
  if (ec) {
    fs::remove_all(tmp, ec);
    throw Error(dir + ": cannot create the output folder (is the parent a writable folder?)");
  }
  try {
    Trajectory gt;
    for (int i = 0; i < seq.size(); ++i) {
      const SyntheticFrame f = seq.frame(i);
      const std::string t = tum_stamp(f.timestamp_s);
      write_color_png(tmp + "/rgb/" + t + ".png", f.color);
      write_depth_png(tmp + "/depth/" + t + ".png", f.depth, 5000.0);
      gt.push_back({f.timestamp_s, f.T_world_camera});
      if (options.progress) options.progress(i + 1, seq.size());
    }
    write_list(tmp + "/rgb.txt", "color", "rgb", seq);
    write_list(tmp + "/depth.txt", "depth", "depth", seq);
    write_tum_trajectory(tmp + "/groundtruth.txt", gt,
                         "ground truth trajectory (T_world_camera) of synthetic '" + seq.options().preset + "'\n" +
                             "timestamp tx ty tz qx qy qz qw");
    seq.camera().save(tmp + "/camera.json");
    if (exists) {
      fs::remove_all(dir, ec);
      if (ec) throw Error(dir + ": cannot remove the existing folder (" + ec.message() + ")");
    }
    fs::rename(tmp, dir, ec);
    if (ec) throw Error(dir + ": cannot move the finished folder into place (" + ec.message() + ")");
  } catch (...) {
    std::error_code ignore;
    fs::remove_all(tmp, ignore);
    throw;
  }
}

}  // namespace hf::datasets
