#include "datasets/tum_writer.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
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

void write_list(const std::string& path, const std::string& what, const std::string& sub, const TumSequence& seq) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# " << what << " images\n# file: '" << seq.list_name << "'\n# timestamp filename\n";
    for (int i = 0; i < seq.frames; ++i) {
      const std::string t = tum_stamp(seq.timestamp_s(i));
      out << t << ' ' << sub << '/' << t << ".png\n";
    }
  });
}

}  // namespace

namespace {

// The entries a previous `generate` leaves; a folder holding anything else is not ours to replace.
bool looks_like_generate_output(const fs::path& dir, std::string& stranger) {
  static const char* const kTop[] = {"rgb", "depth", "rgb.txt", "depth.txt", "groundtruth.txt", "camera.json"};
  std::error_code ec;
  for (const fs::directory_entry& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const bool known = std::find(std::begin(kTop), std::end(kTop), name) != std::end(kTop);
    const fs::file_status st = e.symlink_status(ec);
    const bool is_folder = name == "rgb" || name == "depth";
    if (!known || (is_folder ? !fs::is_directory(st) : !fs::is_regular_file(st))) {
      stranger = name;
      return false;
    }
    if (!is_folder) continue;
    for (const fs::directory_entry& image : fs::directory_iterator(e.path(), ec)) {
      if (image.path().extension() != ".png" || !fs::is_regular_file(image.symlink_status(ec))) {
        stranger = name + "/" + image.path().filename().string();
        return false;
      }
    }
  }
  if (ec) {
    stranger = "(unreadable: " + ec.message() + ")";
    return false;
  }
  if (!fs::exists(dir / "rgb.txt") || !fs::exists(dir / "groundtruth.txt")) {
    stranger = "(no rgb.txt and groundtruth.txt)";
    return false;
  }
  return true;
}

// Folders no command should ever replace: the root, the working folder or one above it, a home folder.
void refuse_precious_folder(const std::string& dir) {
  std::error_code ec;
  const fs::path target = fs::weakly_canonical(fs::absolute(dir, ec), ec);
  if (ec) return;  // it does not resolve: the creation below reports it
  const fs::path cwd = fs::current_path(ec);
  auto is_within = [](const fs::path& inner, const fs::path& outer) {
    auto o = outer.begin();
    for (auto i = inner.begin(); o != outer.end(); ++i, ++o)
      if (i == inner.end() || *i != *o) return false;
    return true;
  };
  std::string why;
  if (target == target.root_path()) why = "the root folder";
  else if (!cwd.empty() && is_within(fs::weakly_canonical(cwd, ec), target)) why = "the working folder or one above it";
  else if (const char* home = std::getenv("HOME"); home && *home && fs::weakly_canonical(home, ec) == target)
    why = "the home folder";
  else if (target.parent_path() == "/home" || target == "/home" || target == "/root") why = "a home folder";
  if (!why.empty()) throw Error(dir + ": refusing to replace " + why + "; choose a folder of its own for --out");
}

}  // namespace

void write_tum_folder(const SyntheticSequence& synthetic, const std::string& dir, const TumWriteOptions& options) {
  TumSequence seq;
  seq.frames = synthetic.size();
  seq.camera = synthetic.camera();
  seq.list_name = "synthetic " + synthetic.options().preset + " seed " + std::to_string(synthetic.options().seed);
  seq.trajectory_name = "synthetic '" + synthetic.options().preset + "'";
  seq.timestamp_s = [&](int i) { return synthetic.timestamp_s(i); };
  seq.frame = [&](int i) { return synthetic.frame(i); };
  write_tum_folder(seq, dir, options);
}

void write_tum_folder(const TumSequence& seq, const std::string& dir_in, const TumWriteOptions& options) {
  if (dir_in.empty()) throw Error("generate: expected a non-empty output folder");
  std::string dir = dir_in;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  refuse_precious_folder(dir);
  std::error_code ec;
  const bool exists = fs::exists(fs::symlink_status(dir, ec));
  if (exists && !options.overwrite) throw Error(dir + ": already exists (choose another folder or overwrite it)");
  if (exists && (fs::is_symlink(fs::symlink_status(dir, ec)) || !fs::is_directory(dir, ec)))
    throw Error(dir + ": exists and is not a folder (a link or a file is not replaced)");
  std::string stranger;
  if (exists && !looks_like_generate_output(dir, stranger))
    throw Error(dir + ": does not look like an output of hashfusion generate (it holds '" + stranger +
                "'); not replacing it");
  // Everything is built in a fresh folder of our own making beside DIR, so nothing else is ever removed.
  std::string tmp;
  try {
    if (const fs::path parent = fs::path(dir).parent_path(); !parent.empty()) fs::create_directories(parent, ec);
    tmp = make_private_folder_beside(dir);
  } catch (const Error&) {
    throw Error(dir + ": cannot create the output folder (is the parent a writable folder?)");
  }
  try {
    fs::create_directories(fs::path(tmp) / "rgb", ec);
    if (!ec) fs::create_directories(fs::path(tmp) / "depth", ec);
    if (ec) throw Error(dir + ": cannot create the output folder (" + ec.message() + ")");
    Trajectory gt;
    for (int i = 0; i < seq.frames; ++i) {
      const SyntheticFrame f = seq.frame(i);
      const std::string t = tum_stamp(f.timestamp_s);
      write_color_png(tmp + "/rgb/" + t + ".png", f.color);
      write_depth_png(tmp + "/depth/" + t + ".png", f.depth, 5000.0);
      gt.push_back({f.timestamp_s, f.T_world_camera});
      if (options.progress) options.progress(i + 1, seq.frames);
    }
    write_list(tmp + "/rgb.txt", "color", "rgb", seq);
    write_list(tmp + "/depth.txt", "depth", "depth", seq);
    write_tum_trajectory(tmp + "/groundtruth.txt", gt,
                         "ground truth trajectory (T_world_camera) of " + seq.trajectory_name + "\n" +
                             "timestamp tx ty tz qx qy qz qw");
    seq.camera.save(tmp + "/camera.json");
  } catch (...) {
    std::error_code ignore;
    fs::remove_all(tmp, ignore);
    throw;
  }
  swap_folder_into_place(tmp, dir);  // removes tmp itself on failure
}

}  // namespace hf::datasets
