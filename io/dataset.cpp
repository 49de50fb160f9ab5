#include "io/dataset.h"

#include <algorithm>
#include <cctype>
#include <filesystem>
#include <sstream>

#include "core/bounded_read.h"
#include "core/error.h"
#include "io/image_header.h"
#include "io/prefetch.h"
#include "io/seven_scenes.h"
#include "io/tum_dataset.h"

namespace fs = std::filesystem;

namespace hf {
namespace {

std::string size_text(int w, int h) { return std::to_string(w) + "x" + std::to_string(h); }

bool file_exists(const fs::path& p) {
  std::error_code ec;
  return fs::is_regular_file(p, ec);
}

std::string folder_name(const std::string& folder) {
  std::error_code ec;
  fs::path p = fs::absolute(fs::path(folder), ec);
  if (ec) p = fs::path(folder);
  p = p.lexically_normal();
  if (p.filename().empty()) p = p.parent_path();
  return p.filename().string();
}

}  // namespace

std::string read_text_file(const std::string& path, const std::string& what) {
  return read_regular_file(path, what, kMaxTextFileBytes);
}

CameraChoice camera_from_option(const std::string& option) {
  const std::vector<std::string> names = PinholeCamera::preset_names();
  if (std::find(names.begin(), names.end(), option) != names.end())
    return {PinholeCamera::preset(option), "preset " + option + " (--camera)"};
  if (file_exists(option)) return {PinholeCamera::load(option), "camera file '" + option + "' (--camera)"};
  std::string known;
  for (const std::string& n : names) known += (known.empty() ? "" : ", ") + n;
  throw Error("--camera '" + option + "': neither a camera preset (" + known + ") nor an existing camera file");
}

std::string preset_from_folder_name(const std::string& folder) {
  std::string name = folder_name(folder);
  std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  // Split into alphanumeric words so that "fr1" matches in "tum_fr1_rpy" but not in "xfr12".
  std::vector<std::string> words;
  std::string word;
  for (char c : name + " ") {
    if (std::isalnum(static_cast<unsigned char>(c))) {
      word += c;
    } else if (!word.empty()) {
      words.push_back(word);
      word.clear();
    }
  }
  for (const std::string& w : words) {
    for (const char* digit : {"1", "2", "3"}) {
      if (w == std::string("freiburg") + digit || w == std::string("fr") + digit) return std::string("fr") + digit;
    }
  }
  return "";
}

CameraChoice choose_tum_camera(const std::string& folder, const std::string& option) {
  if (!option.empty()) return camera_from_option(option);
  for (const char* file : {"camera.json", "camera.txt"}) {
    const fs::path p = fs::path(folder) / file;
    if (file_exists(p)) return {PinholeCamera::load(p.string()), "camera file '" + p.string() + "' in the dataset folder"};
  }
  const std::string preset = preset_from_folder_name(folder);
  // fr1 and fr2 images are stored distorted and the depth is pre-registered to them, which TUM recommends reading
  // as a pinhole (the ROS defaults) rather than undistorting; measured on fr1/rpy (combined, 150 frames) the ROS
  // intrinsics give 1.85 cm ATE against 2.6 cm with the calibrated fr1 ones used without undistortion, and 2.06
  // undistorted (bench/results/accuracy/distortion.md). For fr1 the pinhole itself was then estimated from fr1/rpy
  // frames 0-149 ("fr1-registered": 1.27 cm there; 1.49 on frames 150-269, against 1.69 with the ROS defaults;
  // bench/results/accuracy/intrinsics.md); fr2, of which we hold no recording, keeps the ROS defaults. fr3 was
  // recorded undistorted, so its calibration applies as is.
  if (preset == "fr1")
    return {PinholeCamera::preset("fr1-registered"),
            "preset fr1-registered (folder name '" + folder_name(folder) +
                "' is TUM fr1: distorted images with pre-registered depth, read as the pinhole measured on fr1)"};
  if (preset == "fr2")
    return {PinholeCamera::preset("ros"), "preset ros (folder name '" + folder_name(folder) +
                                              "' is TUM fr2: distorted images with pre-registered depth, read with "
                                              "the ROS defaults as TUM recommends)"};
  if (!preset.empty())
    return {PinholeCamera::preset(preset), "preset " + preset + " (folder name '" + folder_name(folder) + "')"};
  return {PinholeCamera::preset("ros"),
          "preset ros (default: no --camera, no camera.json/camera.txt in the folder, and its name names no TUM "
          "camera)"};
}

CameraChoice choose_seven_scenes_camera(const std::string& folder, const std::string& option) {
  if (!option.empty()) return camera_from_option(option);
  const fs::path p = fs::path(folder) / "camera-intrinsics.txt";
  if (file_exists(p)) {
    const PinholeCamera preset = PinholeCamera::preset("7scenes");
    return {parse_seven_scenes_intrinsics(read_text_file(p.string(), "camera intrinsics"), p.string(), preset.width,
                                          preset.height),
            "camera-intrinsics.txt '" + p.string() + "' (size " + size_text(preset.width, preset.height) +
                " from the 7scenes preset)"};
  }
  return {PinholeCamera::preset("7scenes"), "preset 7scenes (no camera-intrinsics.txt in the folder)"};
}

DatasetFormat detect_dataset_format(const std::string& folder) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) return DatasetFormat::unknown;
  const fs::path dir(folder);
  if (file_exists(dir / "rgb.txt") || file_exists(dir / "depth.txt")) return DatasetFormat::tum;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.rfind("frame-", 0) == 0 && name.size() > 16 && name.compare(name.size() - 10, 10, ".depth.png") == 0)
      return DatasetFormat::seven_scenes;
  }
  return DatasetFormat::unknown;
}

std::string load_frame_images(RgbdFrame& frame, const PinholeCamera& camera, const DepthDecoding& decoding) {
  auto fail = [&](const std::string& message) {
    frame.depth = DepthImage();
    frame.color = ColorImage();
    return message;
  };
  try {
    // The camera's size is checked against each image's header before it is decoded (io/image_io.h).
    const ExpectedImageSize expected{camera.width, camera.height};
    frame.depth = load_depth(frame.depth_file, decoding, expected);
    frame.color = load_color(frame.color_file, expected);
  } catch (const Error& e) {
    return fail(e.what());
  }
  const int dw = frame.depth.width(), dh = frame.depth.height();
  if (dw != frame.color.width() || dh != frame.color.height())
    return fail(frame.depth_file + ": depth image is " + size_text(dw, dh) + " but colour image " + frame.color_file +
                " is " + size_text(frame.color.width(), frame.color.height()));
  if (dw != camera.width || dh != camera.height)
    return fail(frame.depth_file + ": image is " + size_text(dw, dh) + " but the camera is " +
                size_text(camera.width, camera.height));
  return "";
}

std::unique_ptr<FrameSource> open_dataset(const std::string& path, const DatasetOptions& options) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw Error(path + ": dataset folder not found");
  if (!fs::is_directory(path, ec)) throw Error(path + ": expected a dataset folder, got a file");
  std::unique_ptr<FrameSource> source;
  std::string empty_reason;
  switch (detect_dataset_format(path)) {
    case DatasetFormat::tum: {
      auto tum = std::make_unique<TumDataset>(path, options);
      const TumSummary& s = tum->summary();
      empty_reason = std::to_string(s.rgb_entries) + " colour and " + std::to_string(s.depth_entries) +
                     " depth entries, no pair within " + std::to_string(options.association.max_difference_s) + " s";
      source = std::move(tum);
      break;
    }
    case DatasetFormat::seven_scenes:
      source = std::make_unique<SevenScenesDataset>(path, options);
      break;
    case DatasetFormat::unknown:
      throw Error(path +
                  ": unknown dataset layout (expected rgb.txt + depth.txt of TUM RGB-D, or frame-XXXXXX.depth.png "
                  "files of 7-Scenes)");
  }
  if (source->size() == 0)
    throw Error(path + ": dataset has no frames" + (empty_reason.empty() ? "" : " (" + empty_reason + ")"));
  if (options.prefetch_frames > 0)
    source = std::make_unique<PrefetchingSource>(std::move(source), options.prefetch_frames);
  return source;
}

}  // namespace hf
