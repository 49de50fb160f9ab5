#include "io/tum_recorder.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>
#include <vector>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/image_io.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

std::string stamp_text(double t) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6f", t);
  return buf;
}

std::string numbered(long i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06ld.png", i);
  return buf;
}

void write_list(const std::string& path, const std::string& what, const std::string& sub,
                const std::vector<std::string>& stamps, const std::string& source_name) {
  write_file_atomically(path, [&](std::ostream& out) {
    out << "# " << what << " images\n# recorded by hashfusion record from " << source_name
        << "\n# timestamp filename\n";
    for (size_t i = 0; i < stamps.size(); ++i) out << stamps[i] << ' ' << sub << '/' << numbered(long(i)) << '\n';
  });
}

}  // namespace

void check_new_record_folder(const std::string& dir) {
  if (dir.empty()) throw Error("record: expected a non-empty output folder");
  std::error_code ec;
  if (fs::exists(fs::symlink_status(dir, ec)))
    throw Error(dir + ": already exists (record writes a new folder; choose another name)");
}

RecordResult record_tum_folder(FrameSource& source, const std::string& dir_in, const RecordLimits& limits) {
  std::string dir = dir_in;
  while (dir.size() > 1 && dir.back() == '/') dir.pop_back();
  check_new_record_folder(dir);
  std::error_code ec;
  if (const fs::path parent = fs::path(dir).parent_path(); !parent.empty()) fs::create_directories(parent, ec);
  const std::string tmp = make_private_folder_beside(dir);
  RecordResult result;
  try {
    fs::create_directories(fs::path(tmp) / "rgb", ec);
    if (!ec) fs::create_directories(fs::path(tmp) / "depth", ec);
    if (ec) throw Error(dir + ": cannot create the output folder (" + ec.message() + ")");
    std::vector<std::string> stamps;
    std::optional<double> last_stamp;
    const auto start = std::chrono::steady_clock::now();
    for (;;) {
      if (limits.frames > 0 && result.frames >= limits.frames) break;
      if (limits.seconds > 0 &&
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >= limits.seconds)
        break;
      if (limits.stop && limits.stop->load()) {
        result.interrupted = true;
        break;
      }
      FrameRead fr = source.next();
      if (fr.status == FrameStatus::end) {
        result.input_ended = fr.message;
        break;
      }
      // The printed stamp is what the replay sees, so monotonicity is checked on it.
      const std::string t = stamp_text(fr.frame.timestamp_s);
      if (fr.status == FrameStatus::bad_frame || (last_stamp && std::stod(t) <= *last_stamp)) {
        ++result.skipped;
        continue;
      }
      const std::string name = numbered(result.frames);
      write_color_png(tmp + "/rgb/" + name, fr.frame.color);
      write_depth_png(tmp + "/depth/" + name, fr.frame.depth, 5000.0);
      stamps.push_back(t);
      last_stamp = std::stod(t);
      ++result.frames;
      if (limits.progress) limits.progress(result.frames);
    }
    result.capture = source.capture_stats();
    if (result.frames == 0)
      throw Error(dir + ": no frame recorded" + (result.input_ended.empty() ? "" : " (" + result.input_ended + ")") +
                  (result.interrupted ? " (interrupted)" : ""));
    write_list(tmp + "/rgb.txt", "color", "rgb", stamps, source.name());
    write_list(tmp + "/depth.txt", "depth", "depth", stamps, source.name());
    source.camera().save(tmp + "/camera.json");
  } catch (...) {
    std::error_code ignore;
    fs::remove_all(tmp, ignore);
    throw;
  }
  swap_folder_into_place(tmp, dir);
  return result;
}

}  // namespace hf
