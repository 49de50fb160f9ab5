#include "photogrammetry/scene_readers.h"

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>

#include "core/bounded_read.h"
#include "core/error.h"
#include "io/ply.h"
#include "io/trajectory_io.h"
#include "io/tum_dataset.h"
#include "photogrammetry/scene_mvs.h"
#include "photogrammetry/text_lines.h"

namespace hf::photogrammetry {
namespace {

namespace fs = std::filesystem;
using detail::parse_double;
using detail::parse_integer;

bool regular_file(const std::string& path) {
  std::error_code ec;
  return fs::is_regular_file(path, ec);
}

std::string joined(const std::string& root, std::string_view relative) {
  return (fs::path(root) / fs::path(std::string(relative))).lexically_normal().string();
}

// R from nine words in row order.
Eigen::Matrix3d matrix3(const std::vector<std::string_view>& w, size_t first, const std::string& file, int line,
                        const char* what) {
  Eigen::Matrix3d M;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) M(r, c) = parse_double(w[first + size_t(3 * r + c)], file, line, what);
  return M;
}

Network finish(Network n) {
  n.validate();
  return n;
}

}  // namespace

std::vector<Shot> parse_openmvs_cameras(const std::string& text, const std::string& file,
                                        const std::string& image_root) {
  std::vector<Shot> shots;
  detail::for_each_data_line(text, file, [&](const std::vector<std::string_view>& w, int line) {
    if (w.size() != 23)
      throw ParseError(file, line, "expected 23 fields 'image width height fx fy cx cy R00..R22 Cx Cy Cz tx ty tz "
                                   "present', got " + (w.size() > 23 ? std::string("more") : std::to_string(w.size())));
    if (shots.size() == kMaxShots)
      throw ParseError(file, line, "expected at most " + std::to_string(kMaxShots) + " shots, got more");
    Shot s;
    s.name = fs::path(std::string(w[0])).filename().string();
    s.image_path = joined(image_root, w[0]);
    s.width = int(parse_integer(w[1], file, line, "width", 1, 65536));
    s.height = int(parse_integer(w[2], file, line, "height", 1, 65536));
    const double fx = parse_double(w[3], file, line, "fx"), fy = parse_double(w[4], file, line, "fy");
    const double cx = parse_double(w[5], file, line, "cx"), cy = parse_double(w[6], file, line, "cy");
    if (!(fx > 0) || !(fy > 0)) throw ParseError(file, line, "expected positive focal lengths fx, fy");
    s.K << fx, 0, cx, 0, fy, cy, 0, 0, 1;
    s.R_camera_world = matrix3(w, 7, file, line, "R");
    for (int k = 0; k < 3; ++k) s.C_world[k] = parse_double(w[16 + size_t(k)], file, line, "C");
    Eigen::Vector3d t;
    for (int k = 0; k < 3; ++k) t[k] = parse_double(w[19 + size_t(k)], file, line, "t");
    // The dump carries t = -R C redundantly; a mismatch means a corrupt or reordered line.
    if (!((t + s.R_camera_world * s.C_world).norm() <= 1e-6 * std::max(1.0, s.C_world.norm())))
      throw ParseError(file, line, "expected t = -R C (the camera's translation and centre disagree)");
    const long long present = parse_integer(w[22], file, line, "present", 0, 1);
    s.image_available = present == 1 && regular_file(s.image_path);
    shots.push_back(std::move(s));
  });
  return shots;
}

Cloud parse_openmvs_points(const std::string& text, const std::string& file, size_t shot_count) {
  Cloud c;
  detail::for_each_data_line(text, file, [&](const std::vector<std::string_view>& w, int line) {
    if (w.size() < 7) throw ParseError(file, line, "expected 'X Y Z R G B n_views view...', got " +
                                                       std::to_string(w.size()) + " fields");
    if (c.size() == kMaxCloudPoints)
      throw ParseError(file, line, "expected at most " + std::to_string(kMaxCloudPoints) + " points, got more");
    Eigen::Vector3d X;
    for (int k = 0; k < 3; ++k) X[k] = parse_double(w[size_t(k)], file, line, "coordinate");
    Rgb8 rgb;
    rgb.r = std::uint8_t(parse_integer(w[3], file, line, "red", 0, 255));
    rgb.g = std::uint8_t(parse_integer(w[4], file, line, "green", 0, 255));
    rgb.b = std::uint8_t(parse_integer(w[5], file, line, "blue", 0, 255));
    const long long n = parse_integer(w[6], file, line, "view count", 0, (long long)shot_count);
    if (w.size() != 7 + size_t(n))
      throw ParseError(file, line, "expected " + std::to_string(n) + " view indices after the count, got " +
                                       std::to_string(w.size() - 7));
    std::vector<int> views;
    for (long long k = 0; k < n; ++k) {
      const int v = int(parse_integer(w[7 + size_t(k)], file, line, "view index", 0, (long long)shot_count - 1));
      for (const int u : views)
        if (u == v) throw ParseError(file, line, "expected each view once, got view " + std::to_string(v) + " twice");
      views.push_back(v);
    }
    c.positions.push_back(X);
    c.colors.push_back(rgb);
    c.views.push_back(std::move(views));
  });
  return c;
}

Network read_openmvs_text(const std::string& path) {
  std::error_code ec;
  const std::string cameras = fs::is_directory(path, ec) ? joined(path, "cameras_from_scene_mvs.txt") : path;
  const std::string root = fs::path(cameras).parent_path().string();
  Network n;
  n.source = cameras;
  n.shots = parse_openmvs_cameras(read_regular_file(cameras, "OpenMVS camera list"), cameras, root);
  const std::string points = joined(root, "sparse_points_with_views.txt");
  if (regular_file(points))
    n.cloud = parse_openmvs_points(read_regular_file(points, "OpenMVS point list"), points, n.shots.size());
  return finish(std::move(n));
}

std::vector<Shot> parse_middlebury_par(const std::string& text, const std::string& file,
                                       const std::string& image_root, const MiddleburyOptions& options) {
  std::vector<Shot> shots;
  long long expected = -1;
  int last_line = 0;
  detail::for_each_data_line(text, file, [&](const std::vector<std::string_view>& w, int line) {
    last_line = line;
    if (expected < 0) {
      if (w.size() != 1) throw ParseError(file, line, "expected the number of images on the first line");
      expected = parse_integer(w[0], file, line, "image count", 0, (long long)kMaxShots);
      return;
    }
    if (w.size() != 22)
      throw ParseError(file, line, "expected 22 fields 'image k11..k33 r11..r33 t1 t2 t3', got " +
                                       (w.size() > 22 ? std::string("more") : std::to_string(w.size())));
    if ((long long)shots.size() == expected)
      throw ParseError(file, line, "expected " + std::to_string(expected) + " images (the first line), got more");
    Shot s;
    s.name = fs::path(std::string(w[0])).filename().string();
    s.image_path = joined(image_root, w[0]);
    s.width = options.width;
    s.height = options.height;
    s.K = matrix3(w, 1, file, line, "K");
    if (!(s.K(0, 0) > 0) || !(s.K(1, 1) > 0) || s.K(1, 0) != 0 || s.K(2, 0) != 0 || s.K(2, 1) != 0 || s.K(2, 2) != 1)
      throw ParseError(file, line, "expected K = [fx s cx; 0 fy cy; 0 0 1] with fx, fy > 0");
    s.R_camera_world = matrix3(w, 10, file, line, "R");
    Eigen::Vector3d t;
    for (int k = 0; k < 3; ++k) t[k] = parse_double(w[19 + size_t(k)], file, line, "t");
    s.C_world = -s.R_camera_world.transpose() * t;
    s.image_available = regular_file(s.image_path);
    shots.push_back(std::move(s));
  });
  if (expected < 0) throw ParseError(file, 0, "expected the number of images on the first line, got no data");
  if ((long long)shots.size() != expected)
    throw ParseError(file, last_line, "expected " + std::to_string(expected) + " images (the first line), got " +
                                          std::to_string(shots.size()));
  return shots;
}

Network read_middlebury(const std::string& path, const MiddleburyOptions& options) {
  std::string par = path;
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    par.clear();
    for (const auto& e : fs::directory_iterator(path, ec)) {
      const std::string name = e.path().filename().string();
      if (name.size() > 8 && name.compare(name.size() - 8, 8, "_par.txt") == 0) {
        if (!par.empty()) throw Error(path + ": expected one *_par.txt, found two");
        par = e.path().string();
      }
    }
    if (par.empty()) throw Error(path + ": expected a Middlebury *_par.txt in the folder");
  }
  Network n;
  n.source = par;
  n.shots = parse_middlebury_par(read_regular_file(par, "Middlebury camera file"), par,
                                 fs::path(par).parent_path().string(), options);
  return finish(std::move(n));
}

RunReport parse_run_report(const std::string& text, const std::string& file) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError(file, 0, "expected a run's report.json (JSON), got a syntax error at byte " +
                                  std::to_string(e.byte));
  } catch (const nlohmann::json::exception&) {  // e.g. a number beyond double's range (out_of_range 406)
    throw ParseError(file, 0, "expected a run's report.json (JSON), got a number out of range");
  }
  RunReport r;
  if (!j.is_object() || !j.contains("input") || !j["input"].is_string())
    throw ParseError(file, 0, "expected an object with \"input\" (the run's dataset), as hashfusion run writes");
  r.input = j["input"].get<std::string>();
  // "camera": an object {fx, fy, cx, cy, width, height} (issue 36 on), else the string runs wrote before.
  if (j.contains("camera") && j["camera"].is_object()) {
    r.camera = PinholeCamera::parse(j["camera"].dump(), file);
  } else {
    if (!j.contains("camera") || !j["camera"].is_string())
      throw ParseError(file, 0, "expected \"camera\": {\"fx\": .., \"fy\": .., \"cx\": .., \"cy\": .., \"width\": .., "
                                "\"height\": ..} or \"fx=.. fy=.. cx=.. cy=.. WxH\"");
    const std::string cam = j["camera"].get<std::string>();
    static const std::regex pattern(
        R"(fx=(\S+) fy=(\S+) cx=(\S+) cy=(\S+) ([0-9]{1,5})x([0-9]{1,5}))");
    std::smatch m;
    if (cam.size() > 200 || !std::regex_match(cam, m, pattern))
      throw ParseError(file, 0, "expected \"camera\": \"fx=.. fy=.. cx=.. cy=.. WxH\", got " + quote_for_message(cam));
    r.camera.fx = parse_double(m.str(1), file, 0, "camera fx");
    r.camera.fy = parse_double(m.str(2), file, 0, "camera fy");
    r.camera.cx = parse_double(m.str(3), file, 0, "camera cx");
    r.camera.cy = parse_double(m.str(4), file, 0, "camera cy");
    r.camera.width = int(parse_integer(m.str(5), file, 0, "camera width", 1, 65536));
    r.camera.height = int(parse_integer(m.str(6), file, 0, "camera height", 1, 65536));
    if (!(r.camera.fx > 0) || !(r.camera.fy > 0)) throw ParseError(file, 0, "expected positive camera focal lengths");
  }
  if (!j.contains("per_frame") || !j["per_frame"].is_array())
    throw ParseError(file, 0, "expected \"per_frame\": [...] (the run's frames)");
  size_t k = 0;
  for (const auto& f : j["per_frame"]) {
    if (!f.is_object() || !f.contains("timestamp_s") || !f["timestamp_s"].is_number() ||
        !std::isfinite(f["timestamp_s"].get<double>()))
      throw ParseError(file, 0, "expected per_frame[" + std::to_string(k) + "] to have a finite \"timestamp_s\"");
    const double t = f["timestamp_s"].get<double>();
    const bool keyframe = f.contains("keyframe") && f["keyframe"].is_boolean() && f["keyframe"].get<bool>();
    const bool lost = f.contains("state") && f["state"].is_string() && f["state"].get<std::string>() == "lost";
    if (keyframe) r.keyframe_stamps_s.push_back(t);
    if (!lost) r.tracked_stamps_s.push_back(t);
    if (++k > kMaxShots * 100) throw ParseError(file, 0, "expected fewer frames than the limit");
  }
  return r;
}

Network read_run_network(const std::string& run_dir, const RunShotsOptions& options) {
  const std::string report_path = joined(run_dir, "report.json");
  const RunReport report = parse_run_report(read_regular_file(report_path, "run report"), report_path);
  const std::string trajectory_path = joined(run_dir, "trajectory.txt");
  const Trajectory trajectory = read_tum_trajectory(trajectory_path);
  const std::string dataset = options.dataset.empty() ? report.input : options.dataset;
  std::error_code ec;
  if (!fs::is_directory(dataset, ec))
    throw Error(dataset + ": the run's dataset folder (report.json \"input\") is not there; give it with --dataset");
  DatasetOptions d;
  d.prefetch_frames = 0;
  const TumDataset tum(dataset, d);
  Network n;
  n.source = run_dir;
  const std::vector<double>& stamps = options.keyframes_only ? report.keyframe_stamps_s : report.tracked_stamps_s;
  const PinholeCamera& cam = report.camera;
  size_t ti = 0, fi = 0;
  const auto& frames = tum.frames();
  for (const double t : stamps) {
    // Both lists are sorted by time; stamps were written at full precision, so equal up to rounding.
    while (ti < trajectory.size() && trajectory[ti].timestamp_s < t - 1e-6) ++ti;
    while (fi < frames.size() && frames[fi].timestamp_s < t - 1e-6) ++fi;
    if (ti == trajectory.size() || std::fabs(trajectory[ti].timestamp_s - t) > 1e-6)
      throw Error(trajectory_path + ": no pose at the report's frame stamp " + std::to_string(t));
    if (fi == frames.size() || std::fabs(frames[fi].timestamp_s - t) > 1e-6)
      throw Error(dataset + ": no colour image at the run's frame stamp " + std::to_string(t) +
                  " (is it the run's dataset?)");
    Shot s;
    s.image_path = frames[fi].color_file;
    s.name = fs::path(s.image_path).filename().string();
    s.image_available = regular_file(s.image_path);
    s.width = cam.width;
    s.height = cam.height;
    s.K = cam.K();
    const SE3& T = trajectory[ti].T_world_camera;
    s.R_camera_world = T.rotation().transpose();
    s.C_world = T.translation();
    n.shots.push_back(std::move(s));
  }
  const std::string mesh = joined(run_dir, "mesh.ply");
  if (regular_file(mesh)) {
    const PointCloud cloud = read_ply_point_cloud(mesh);
    for (const auto& p : cloud.positions) n.cloud.positions.push_back(p.cast<double>());
    n.cloud.colors = cloud.colors;
  }
  return finish(std::move(n));
}

Network read_network(const std::string& path, const RunShotsOptions& run_options) {
  std::error_code ec;
  if (fs::is_directory(path, ec)) {
    if (regular_file(joined(path, "report.json"))) return read_run_network(path, run_options);
    if (regular_file(joined(path, "cameras_from_scene_mvs.txt"))) return read_openmvs_text(path);
    if (regular_file(joined(path, "scene.mvs"))) return read_scene_mvs(joined(path, "scene.mvs"));
    for (const auto& e : fs::directory_iterator(path, ec)) {
      const std::string name = e.path().filename().string();
      if (name.size() > 8 && name.compare(name.size() - 8, 8, "_par.txt") == 0) return read_middlebury(path);
    }
    throw Error(path + ": expected a hashfusion run folder (report.json), an OpenMVS dump "
                       "(cameras_from_scene_mvs.txt) or scene (scene.mvs), or a Middlebury folder (*_par.txt)");
  }
  if (!regular_file(path)) throw Error(path + ": no such shots file or folder");
  const std::string name = fs::path(path).filename().string();
  if (name.size() > 8 && name.compare(name.size() - 8, 8, "_par.txt") == 0) return read_middlebury(path);
  if (name == "report.json") return read_run_network(fs::path(path).parent_path().string(), run_options);
  if (name.size() > 4 && name.compare(name.size() - 4, 4, ".mvs") == 0) return read_scene_mvs(path);
  return read_openmvs_text(path);
}

}  // namespace hf::photogrammetry
