#include "core/camera.h"

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/atomic_file.h"
#include "core/bounded_read.h"
#include "core/camera_bounds.h"
#include "core/error.h"
#include "core/number_text.h"

namespace hf {
namespace {

const std::map<std::string, PinholeCamera>& presets() {
  // TUM values from the TUM RGB-D "file formats" page (Kinect factory calibration, depth registered to colour).
  static const std::map<std::string, PinholeCamera> table = {
      {"ros", {525.0, 525.0, 319.5, 239.5, 640, 480}},
      {"fr1", {517.3, 516.5, 318.6, 255.3, 640, 480, {0.2624, -0.9531, -0.0054, 0.0026, 1.1633}}},
      // fr1's stored images (distorted colour, depth pre-registered to it) read as one pinhole: the intrinsics that
      // track fr1/rpy frames 0-149 best against its reference (ATE 1.85 -> 1.27 cm; reported on 150-269: 1.69 ->
      // 1.49, 0-269: 2.41 -> 1.95; bench/results/accuracy/intrinsics.md). Near TUM's calibration seen through its
      // lens (the radial factor is ~1.02 at mid-field: 517 -> ~530 px; cy 255) but for cx, ~9 px left of it.
      {"fr1-registered", {532.0, 532.0, 309.5, 250.0, 640, 480}},
      {"fr2", {520.9, 521.0, 325.1, 249.7, 640, 480, {0.2312, -0.7849, -0.0033, -0.0001, 0.9172}}},
      {"fr3", {535.4, 539.2, 320.1, 247.6, 640, 480}},
      {"icl-nuim", {481.2, 480.0, 319.5, 239.5, 640, 480}},
      {"7scenes", {585.0, 585.0, 320.0, 240.0, 640, 480}},
  };
  return table;
}

// The line of a JSON key's first occurrence ("\"fx\""), so a bad value can be placed in the file; 0 when absent.
int camera_json_key_line(const std::string& text, const std::string& key) {
  const size_t at = text.find('"' + key + '"');
  return at == std::string::npos ? 0 : 1 + int(std::count(text.begin(), text.begin() + long(at), '\n'));
}

const char* const kCameraRequiredKeys[] = {"fx", "fy", "cx", "cy", "width", "height"};
const char* const kCameraDistortionKeys[] = {"k1", "k2", "p1", "p2", "k3"};

bool is_camera_key(const std::string& key) {
  for (const char* k : kCameraRequiredKeys)
    if (key == k) return true;
  for (const char* k : kCameraDistortionKeys)
    if (key == k) return true;
  return false;
}

double& camera_distortion_field(LensDistortion& d, const std::string& key) {
  return key == "k1" ? d.k1 : key == "k2" ? d.k2 : key == "p1" ? d.p1 : key == "p2" ? d.p2 : d.k3;
}

}  // namespace

void check_lens_distortion(const PinholeCamera& c, const std::string& file, const std::map<std::string, int>& lines) {
  auto line = [&](const char* key) {
    const auto it = lines.find(key);
    return it == lines.end() ? 0 : it->second;
  };
  const LensDistortion& d = c.distortion;
  auto bound = [&](const char* key, double v, double max) {
    if (!(std::abs(v) <= max))
      throw ParseError(file, line(key), std::string("expected ") + key + " within " + number_for_message(-max) +
                                            ".." + number_for_message(max) + ", got " + number_for_message(v));
  };
  bound("k1", d.k1, kMaxRadialDistortion);
  bound("k2", d.k2, kMaxRadialDistortion);
  bound("k3", d.k3, kMaxRadialDistortion);
  bound("p1", d.p1, kMaxTangentialDistortion);
  bound("p2", d.p2, kMaxTangentialDistortion);
  // The radial image radius r (1 + k1 r^2 + k2 r^4 + k3 r^6) must grow with r out to the farthest image corner,
  // or two rays land on one pixel and the undistortion remap is not a function. Its derivative is a polynomial in
  // r^2; 1024 steps resolve any sign change of a well-scaled one, and the coefficients are bounded above.
  const double xs[] = {(0.0 - c.cx) / c.fx, (c.width - 1.0 - c.cx) / c.fx};
  const double ys[] = {(0.0 - c.cy) / c.fy, (c.height - 1.0 - c.cy) / c.fy};
  double r2_max = 0.0;
  for (double x : xs)
    for (double y : ys) r2_max = std::max(r2_max, x * x + y * y);
  for (int i = 1; i <= 1024; ++i) {
    const double r2 = r2_max * i / 1024.0;
    const double slope = 1.0 + r2 * (3.0 * d.k1 + r2 * (5.0 * d.k2 + r2 * 7.0 * d.k3));
    if (!(slope > 0.0))
      throw ParseError(file, line("k1"), "expected a distortion whose image radius grows with the ray's angle over "
                                         "the whole image, got k1 k2 k3 = " + number_for_message(d.k1) + " " +
                                         number_for_message(d.k2) + " " + number_for_message(d.k3) +
                                         ", which folds back at normalised radius " +
                                         number_for_message(std::sqrt(r2)) + " (the corners reach " +
                                         number_for_message(std::sqrt(r2_max)) + ")");
  }
}

void check_camera_intrinsics(const PinholeCamera& c, const std::string& file, const std::map<std::string, int>& lines) {
  auto line = [&](const char* key) {
    const auto it = lines.find(key);
    return it == lines.end() ? 0 : it->second;
  };
  auto focal = [&](const char* key, double f, int size) {
    const double lo = size * kMinFocalPerPixel, hi = size * kMaxFocalPerPixel;
    if (!(f >= lo && f <= hi))
      throw ParseError(file, line(key), std::string("expected ") + key + " within " + number_for_message(lo) + ".." +
                                            number_for_message(hi) + " px (fields of view 0.5..170 degrees over " +
                                            std::to_string(size) + " px), got " + number_for_message(f));
  };
  auto centre = [&](const char* key, double v, int size) {
    if (!(v >= -size && v <= 2.0 * size))
      throw ParseError(file, line(key),
                       std::string("expected ") + key + " within " + std::to_string(-size) + ".." +
                           std::to_string(2 * size) + " px (the principal point near the image), got " +
                           number_for_message(v));
  };
  focal("fx", c.fx, c.width);
  focal("fy", c.fy, c.height);
  centre("cx", c.cx, c.width);
  centre("cy", c.cy, c.height);
}

Eigen::Matrix3d PinholeCamera::K() const {
  Eigen::Matrix3d K;
  K << fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0;
  return K;
}

PinholeCamera PinholeCamera::scaled(int level) const {
  PinholeCamera c = *this;
  for (int l = 0; l < level; ++l) {
    c.fx *= 0.5;
    c.fy *= 0.5;
    c.cx = (c.cx + 0.5) * 0.5 - 0.5;
    c.cy = (c.cy + 0.5) * 0.5 - 0.5;
    c.width /= 2;
    c.height /= 2;
  }
  return c;
}

PinholeCamera PinholeCamera::preset(const std::string& name) {
  auto it = presets().find(name);
  if (it == presets().end()) {
    std::string known;
    for (const auto& [k, v] : presets()) known += (known.empty() ? "" : ", ") + k;
    throw Error("unknown camera preset '" + name + "' (known: " + known + ")");
  }
  return it->second;
}

std::vector<std::string> PinholeCamera::preset_names() {
  std::vector<std::string> names;
  for (const auto& [k, v] : presets()) names.push_back(k);
  return names;
}

PinholeCamera PinholeCamera::parse(const std::string& text, const std::string& file) {
  PinholeCamera c;
  std::map<std::string, int> lines;  // the line of each key, for bounds checked after all are read
  size_t first = text.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && text[first] == '{') {
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(text);
    } catch (const nlohmann::json::parse_error& e) {
      // nlohmann reports a byte offset; turn it into a line number for the message.
      const size_t byte = std::min<size_t>(e.byte, text.size());
      const int line = 1 + int(std::count(text.begin(), text.begin() + long(byte), '\n'));
      throw ParseError(file, line, "expected a JSON camera object");
    }  catch (const nlohmann::json::exception& e) {
      // e.g. a number too large for a double (1e400): out_of_range, not parse_error.
      const std::string what = e.what();  // "[json.exception.out_of_range.406] number overflow parsing '1e400'"
      const size_t tag_end = what.find("] ");
      throw ParseError(file, 0, "expected a JSON camera object, got " +
                                    quote_for_message(tag_end == std::string::npos ? what : what.substr(tag_end + 2)));
    }
    auto num = [&](const char* key) -> double {
      if (!j.is_object() || !j.contains(key) || !j[key].is_number())
        throw ParseError(file, camera_json_key_line(text, key), std::string("expected a number '") + key + "'");
      lines[key] = camera_json_key_line(text, key);
      return j[key].get<double>();
    };
    // An unknown key is a calibration this reader would silently ignore ("k4": a model with more terms), as
    // --config refuses.
    if (j.is_object())
      for (const auto& item : j.items())
        if (!is_camera_key(item.key()))
          throw ParseError(file, camera_json_key_line(text, item.key()),
                           "expected only the keys fx fy cx cy width height k1 k2 p1 p2 k3, got " +
                               quote_for_message(item.key()));
    c.fx = num("fx");
    c.fy = num("fy");
    c.cx = num("cx");
    c.cy = num("cy");
    const double w = num("width"), h = num("height");
    if (!(w >= 1 && w <= 16384 && h >= 1 && h <= 16384) || w != std::floor(w) || h != std::floor(h))
      throw ParseError(file, 0, "expected integer width and height in 1..16384");
    c.width = int(w);
    c.height = int(h);
    for (const char* key : kCameraDistortionKeys)
      if (j.contains(key)) camera_distortion_field(c.distortion, key) = num(key);
  } else {
    std::istringstream in(text);
    std::string line;
    int lineno = 0;
    std::map<std::string, double> values;
    while (std::getline(in, line)) {
      ++lineno;
      const size_t hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream ls(line);
      std::string key;
      if (!(ls >> key)) continue;
      double value;
      if (!(ls >> value) || !std::isfinite(value))
        throw ParseError(file, lineno, "expected " + quote_for_message(key + " <number>") + ", got " + quote_for_message(line));
      std::string rest;
      if (ls >> rest)
        throw ParseError(file, lineno, "expected one value after " + quote_for_message(key) + ", got " + quote_for_message(rest));
      if (!is_camera_key(key))
        throw ParseError(file, lineno,
                         "expected one of fx fy cx cy width height k1 k2 p1 p2 k3, got " + quote_for_message(key));
      if (lines.count(key))  // two fx lines: which one is the calibration? Neither silently.
        throw ParseError(file, lineno, "'" + key + "' given twice (first on line " + std::to_string(lines[key]) + ")");
      lines[key] = lineno;
      values[key] = value;
    }
    for (const char* key : {"fx", "fy", "cx", "cy", "width", "height"}) {
      if (!values.count(key)) throw ParseError(file, 0, std::string("missing '") + key + "'");
    }
    c.fx = values["fx"];
    c.fy = values["fy"];
    c.cx = values["cx"];
    c.cy = values["cy"];
    const double w = values["width"], h = values["height"];
    if (!(w >= 1 && w <= 16384 && h >= 1 && h <= 16384) || w != std::floor(w) || h != std::floor(h))
      throw ParseError(file, 0, "expected integer width and height in 1..16384");
    c.width = int(values["width"]);
    c.height = int(values["height"]);
    for (const char* key : kCameraDistortionKeys)
      if (values.count(key)) camera_distortion_field(c.distortion, key) = values[key];
  }
  check_camera_intrinsics(c, file, lines);
  check_lens_distortion(c, file, lines);
  return c;
}

PinholeCamera PinholeCamera::load(const std::string& path) {
  return parse(read_regular_file(path, "camera file"), path);
}

void PinholeCamera::save(const std::string& path) const {
  nlohmann::json j = {{"fx", fx}, {"fy", fy}, {"cx", cx}, {"cy", cy}, {"width", width}, {"height", height}};
  if (!distortion.none()) {
    j["k1"] = distortion.k1;
    j["k2"] = distortion.k2;
    j["p1"] = distortion.p1;
    j["p2"] = distortion.p2;
    j["k3"] = distortion.k3;
  }
  write_file_atomically(path, [&](std::ostream& out) { out << j.dump(2) << "\n"; });
}

std::string PinholeCamera::describe() const {
  std::ostringstream s;
  s << "fx=" << fx << " fy=" << fy << " cx=" << cx << " cy=" << cy << " " << width << "x" << height;
  if (!distortion.none())
    s << " k1=" << distortion.k1 << " k2=" << distortion.k2 << " p1=" << distortion.p1 << " p2=" << distortion.p2
      << " k3=" << distortion.k3;
  return s.str();
}

}  // namespace hf
