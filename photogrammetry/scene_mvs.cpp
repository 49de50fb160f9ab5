#include "photogrammetry/scene_mvs.h"

#include <cmath>
#include <cstring>
#include <filesystem>

#include "core/bounded_read.h"
#include "core/error.h"
#include "photogrammetry/scene_readers.h"

namespace hf::photogrammetry {
namespace {

namespace fs = std::filesystem;

constexpr std::uint32_t kNoId = 0xFFFFFFFFu;
constexpr std::uint64_t kMaxStringBytes = 4096;
constexpr size_t kMaxPlatforms = 100000;

struct Camera {
  std::uint32_t width = 0, height = 0;
  Eigen::Matrix3d K, R;
  Eigen::Vector3d C;
};
struct Pose {
  Eigen::Matrix3d R;
  Eigen::Vector3d C;
};
struct Platform {
  std::vector<Camera> cameras;
  std::vector<Pose> poses;
};

// Little-endian reads over the bytes with the position in every message.
class Reader {
 public:
  Reader(std::string_view bytes, const std::string& file) : bytes_(bytes), file_(file) {}

  [[noreturn]] void fail(const std::string& expected) const {
    throw ParseError(file_, 0, "at byte " + std::to_string(at_) + ": expected " + expected);
  }
  size_t left() const { return bytes_.size() - at_; }
  size_t at() const { return at_; }
  void skip(size_t n, const char* what) {
    if (n > left()) fail(std::string(what) + " (" + std::to_string(n) + " bytes), got the end of the file");
    at_ += n;
  }
  template <typename T>
  T scalar(const char* what) {
    if (sizeof(T) > left()) fail(std::string(what) + ", got the end of the file");
    T v;
    std::memcpy(&v, bytes_.data() + at_, sizeof(T));  // the format is little-endian, as every host we build for
    at_ += sizeof(T);
    return v;
  }
  double finite(const char* what) {
    const double v = scalar<double>(what);
    if (!std::isfinite(v)) fail(std::string("a finite ") + what);
    return v;
  }
  // An array's element count; each element takes at least min_bytes, so a count the rest cannot hold is refused
  // before anything is allocated.
  size_t count(const char* what, size_t min_bytes, size_t limit) {
    const std::uint64_t n = scalar<std::uint64_t>(what);
    if (n > limit) fail(std::string(what) + " of at most " + std::to_string(limit) + ", got " + std::to_string(n));
    if (min_bytes > 0 && n > left() / min_bytes)
      fail(std::string(what) + " that the file's remaining " + std::to_string(left()) + " bytes can hold, got " +
           std::to_string(n));
    return size_t(n);
  }
  std::string string(const char* what) {
    const size_t n = count(what, 1, kMaxStringBytes);
    std::string s(bytes_.substr(at_, n));
    at_ += n;
    return s;
  }
  Eigen::Matrix3d matrix3(const char* what) {
    Eigen::Matrix3d M;
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) M(r, c) = finite(what);
    return M;
  }
  Eigen::Vector3d vector3(const char* what) {
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) v[k] = finite(what);
    return v;
  }
  Eigen::Vector3d vector3f(const char* what) {
    Eigen::Vector3d v;
    for (int k = 0; k < 3; ++k) {
      v[k] = double(scalar<float>(what));
      if (!std::isfinite(v[k])) fail(std::string("a finite ") + what);
    }
    return v;
  }

 private:
  std::string_view bytes_;
  const std::string& file_;
  size_t at_ = 0;
};

unsigned read_header(Reader& in, std::string_view bytes) {
  if (bytes.substr(0, 4) != "MVSI") return 0;  // the first version had no header
  in.skip(4, "the \"MVSI\" project id");
  const std::uint32_t version = in.scalar<std::uint32_t>("the version");
  if (version > kMaxSceneMvsVersion)
    in.fail("a scene version up to " + std::to_string(kMaxSceneMvsVersion) + ", got " + std::to_string(version));
  in.scalar<std::uint32_t>("the reserved word");
  return version;
}

// Smallest encodings, for the counts' plausibility checks.
constexpr size_t kCameraBytes = 8 + 18 * 8 + 3 * 8, kPoseBytes = 12 * 8, kImageBytes = 8 + 3 * 4;
constexpr size_t kViewBytes = 8, kVertexBytes = 12 + 8;

std::vector<Platform> read_platforms(Reader& in, unsigned version) {
  std::vector<Platform> platforms(in.count("a platform count", 24, kMaxPlatforms));
  for (Platform& p : platforms) {
    in.string("the platform name");
    p.cameras.resize(in.count("a camera count", kCameraBytes, kMaxShots));
    for (Camera& c : p.cameras) {
      in.string("the camera name");
      if (version >= 4) in.string("the camera band name");
      if (version >= 1) {
        c.width = in.scalar<std::uint32_t>("the camera width");
        c.height = in.scalar<std::uint32_t>("the camera height");
      }
      c.K = in.matrix3("K");
      c.R = in.matrix3("the camera's R");
      c.C = in.vector3("the camera's C");
    }
    p.poses.resize(in.count("a pose count", kPoseBytes, kMaxShots));
    for (Pose& pose : p.poses) {
      pose.R = in.matrix3("the pose's R");
      pose.C = in.vector3("the pose's C");
    }
  }
  return platforms;
}

std::string image_path(const std::string& root, const std::string& name) {
  const fs::path p(name);
  return (p.is_absolute() ? p : fs::path(root) / p).lexically_normal().string();
}

// The images as shots; shot_of[i] is image i's shot, or -1 for an image without a pose.
std::vector<Shot> read_images(Reader& in, unsigned version, const std::vector<Platform>& platforms,
                              const std::string& root, std::vector<int>* shot_of) {
  const size_t n = in.count("an image count", kImageBytes, kMaxShots);
  std::vector<Shot> shots;
  for (size_t i = 0; i < n; ++i) {
    const std::string name = in.string("the image name");
    if (version >= 5) in.string("the mask name");
    const std::uint32_t platform = in.scalar<std::uint32_t>("the platform id");
    const std::uint32_t camera = in.scalar<std::uint32_t>("the camera id");
    const std::uint32_t pose = in.scalar<std::uint32_t>("the pose id");
    if (version >= 3) in.scalar<std::uint32_t>("the image id");
    if (version >= 7) {
      in.skip(3 * 4, "the image's depth range");
      in.skip(in.count("a view score count", 24, kMaxShots) * 24, "the view scores");
    }
    if (pose == kNoId) {
      shot_of->push_back(-1);
      continue;
    }
    const std::string image = "image " + std::to_string(i) + " " + quote_for_message(name) + ": ";
    if (platform >= platforms.size() || camera >= platforms[platform].cameras.size() ||
        pose >= platforms[platform].poses.size())
      in.fail(image + "platform, camera and pose ids inside the file's platforms (got " + std::to_string(platform) +
              ", " + std::to_string(camera) + ", " + std::to_string(pose) + ")");
    const Camera& c = platforms[platform].cameras[camera];
    const Pose& p = platforms[platform].poses[pose];
    if (c.width == 0 || c.height == 0)
      in.fail(image + "a camera with its resolution (a normalised K without width and height is not supported)");
    if (c.width > 65536 || c.height > 65536)
      in.fail(image + "a camera of at most 65536 x 65536 pixels, got " + std::to_string(c.width) + " x " +
              std::to_string(c.height));
    Shot s;
    s.name = fs::path(name).filename().string();
    s.image_path = image_path(root, name);
    std::error_code ec;
    s.image_available = fs::is_regular_file(s.image_path, ec);
    s.width = int(c.width);
    s.height = int(c.height);
    s.K = c.K;
    s.R_camera_world = c.R * p.R;
    s.C_world = p.R.transpose() * c.C + p.C;
    shot_of->push_back(int(shots.size()));
    shots.push_back(std::move(s));
  }
  return shots;
}

Cloud read_vertices(Reader& in, const std::vector<int>& shot_of) {
  Cloud cloud;
  const size_t n = in.count("a vertex count", kVertexBytes, kMaxCloudPoints);
  cloud.positions.reserve(n);
  cloud.views.reserve(n);
  for (size_t i = 0; i < n; ++i) {
    cloud.positions.push_back(in.vector3f("vertex coordinate"));
    const size_t views = in.count("a view count", kViewBytes, shot_of.size());
    std::vector<int> shots;
    for (size_t k = 0; k < views; ++k) {
      const std::uint32_t image = in.scalar<std::uint32_t>("a view's image id");
      in.scalar<float>("a view's confidence");
      if (image >= shot_of.size())
        in.fail("vertex " + std::to_string(i) + ": view image ids below " + std::to_string(shot_of.size()) +
                ", got " + std::to_string(image));
      const int s = shot_of[image];
      if (s < 0) continue;  // an image without a pose
      for (const int u : shots)
        if (u == s) in.fail("vertex " + std::to_string(i) + ": each image once, got image " +
                            std::to_string(image) + " twice");
      shots.push_back(s);
    }
    cloud.views.push_back(std::move(shots));
  }
  return cloud;
}

void skip_array(Reader& in, const char* what, size_t element_bytes) {
  in.skip(in.count(what, element_bytes, kMaxCloudPoints) * element_bytes, what);
}

}  // namespace

Network parse_scene_mvs(std::string_view bytes, const std::string& file, const std::string& image_root) {
  Reader in(bytes, file);
  const unsigned version = read_header(in, bytes);
  const std::vector<Platform> platforms = read_platforms(in, version);
  Network n;
  n.source = file;
  std::vector<int> shot_of;
  n.shots = read_images(in, version, platforms, image_root, &shot_of);
  n.cloud = read_vertices(in, shot_of);
  skip_array(in, "a vertex normal count", 12);
  const size_t colours = in.count("a vertex colour count", 3, kMaxCloudPoints);
  if (colours != 0 && colours != n.cloud.size())
    in.fail("no vertex colours or one per vertex (" + std::to_string(n.cloud.size()) + "), got " +
            std::to_string(colours));
  for (size_t i = 0; i < colours; ++i) {
    Rgb8 c;
    c.b = in.scalar<std::uint8_t>("a colour");  // OpenMVS stores B, G, R
    c.g = in.scalar<std::uint8_t>("a colour");
    c.r = in.scalar<std::uint8_t>("a colour");
    n.cloud.colors.push_back(c);
  }
  if (version >= 1) {
    const size_t lines = in.count("a line count", 24 + 8, kMaxCloudPoints);
    for (size_t i = 0; i < lines; ++i) {
      in.skip(24, "a line's end points");
      in.skip(in.count("a line's view count", kViewBytes, kMaxShots) * kViewBytes, "a line's views");
    }
    skip_array(in, "a line normal count", 12);
    skip_array(in, "a line colour count", 3);
  }
  if (version >= 2) in.skip(16 * 8, "the transform");
  if (version >= 6) in.skip(15 * 8, "the oriented bounding box");
  if (in.left() != 0) in.fail("the end of the scene, got " + std::to_string(in.left()) + " more bytes");
  n.validate();
  return n;
}

Network read_scene_mvs(const std::string& path) {
  return parse_scene_mvs(read_regular_file(path, "OpenMVS scene", kMaxModelFileBytes), path,
                         fs::path(path).parent_path().string());
}

}  // namespace hf::photogrammetry
