#include "io/v4l2_capture.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>

#include "core/error.h"
#include "io/dataset.h"
#include "io/frame_pairing.h"
#include "io/pixel_formats.h"

namespace hf {
namespace {

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r == -1 && errno == EINTR);
  return r;
}

std::string existing_nodes() {
  std::vector<std::string> nodes;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/dev", ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("video", 0) == 0) nodes.push_back(e.path().string());
  }
  std::sort(nodes.begin(), nodes.end());
  std::string s;
  for (const auto& n : nodes) s += (s.empty() ? "" : ", ") + n;
  return s.empty() ? "none" : s;
}

std::vector<std::uint32_t> node_formats(int fd) {
  std::vector<std::uint32_t> formats;
  for (std::uint32_t i = 0; i < 64; ++i) {
    v4l2_fmtdesc d{};
    d.index = i;
    d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd, VIDIOC_ENUM_FMT, &d) != 0) break;
    formats.push_back(d.pixelformat);
  }
  return formats;
}

std::string formats_text(const std::vector<std::uint32_t>& formats) {
  std::string s;
  for (std::uint32_t f : formats) s += (s.empty() ? "" : ", ") + fourcc_text(f);
  return s.empty() ? "none" : s;
}

// One streaming node.
class V4l2Node {
 public:
  V4l2Node(const std::string& path, const LiveInputOptions& o) : path_(path) {
    std::error_code ec;
    if (!std::filesystem::exists(path, ec))
      throw Error("v4l2://" + path + ": no such node; present: " + existing_nodes());
    fd_ = ::open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) throw Error("v4l2://" + path + ": cannot open (" + std::strerror(errno) + ")");
    v4l2_capability cap{};
    if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) != 0) fail("not a V4L2 device (VIDIOC_QUERYCAP: " + errno_text() + ")");
    const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE) || !(caps & V4L2_CAP_STREAMING))
      fail("not a streaming video capture node (a metadata or output node?)");
    card_ = reinterpret_cast<const char*>(cap.card);
    const std::vector<std::uint32_t> offered = node_formats(fd_);
    static const PixelFormat kPreference[] = {PixelFormat::z16,   PixelFormat::yuyv,  PixelFormat::uyvy,
                                              PixelFormat::rgb24, PixelFormat::bgr24, PixelFormat::mjpeg,
                                              PixelFormat::nv12};
    std::optional<std::uint32_t> chosen;
    for (PixelFormat want : kPreference) {
      for (std::uint32_t f : offered)
        if (pixel_format_from_v4l2(f) == want) {
          chosen = f;
          break;
        }
      if (chosen) break;
    }
    if (!chosen) fail("no format hashfusion reads; it offers " + formats_text(offered));
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    fmt.fmt.pix.width = std::uint32_t(o.width);
    fmt.fmt.pix.height = std::uint32_t(o.height);
    fmt.fmt.pix.pixelformat = *chosen;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(fd_, VIDIOC_S_FMT, &fmt) != 0) fail("cannot set " + fourcc_text(*chosen) + " (" + errno_text() + ")");
    if (int(fmt.fmt.pix.width) != o.width || int(fmt.fmt.pix.height) != o.height)
      fail("no " + std::to_string(o.width) + "x" + std::to_string(o.height) + " mode in " + fourcc_text(*chosen) +
           " (the driver offers " + std::to_string(fmt.fmt.pix.width) + "x" + std::to_string(fmt.fmt.pix.height) +
           "; formats " + formats_text(offered) + ")");
    format_ = *pixel_format_from_v4l2(fmt.fmt.pix.pixelformat);
    width_ = o.width;
    height_ = o.height;
    stride_ = fmt.fmt.pix.bytesperline;
    v4l2_streamparm parm{};
    parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    parm.parm.capture.timeperframe.numerator = 1;
    parm.parm.capture.timeperframe.denominator = std::uint32_t(std::max(1, o.fps));
    xioctl(fd_, VIDIOC_S_PARM, &parm);  // best effort: many drivers fix the rate per mode
    map_buffers();
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) != 0) fail("cannot start streaming (" + errno_text() + ")");
    streaming_ = true;
  }

  ~V4l2Node() {
    if (streaming_) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      xioctl(fd_, VIDIOC_STREAMOFF, &type);
    }
    for (auto& b : buffers_)
      if (b.first != MAP_FAILED) ::munmap(b.first, b.second);
    if (fd_ >= 0) ::close(fd_);
  }
  V4l2Node(const V4l2Node&) = delete;
  V4l2Node& operator=(const V4l2Node&) = delete;

  bool is_depth() const { return format_ == PixelFormat::z16; }
  int fd() const { return fd_; }
  std::string describe() const {
    return "'" + card_ + "' (v4l2://" + path_ + ", " + to_string(format_) + " " + std::to_string(width_) + "x" +
           std::to_string(height_) + ")";
  }
  const std::string& path() const { return path_; }
  int width() const { return width_; }
  int height() const { return height_; }

  // Dequeues one filled buffer (poll said it is readable), decodes it with `decode`, and queues it again.
  // Returns false with `error` set when the node failed; true otherwise (nothing decoded on EAGAIN or for a
  // corrupt buffer).
  template <class Decode>
  bool dequeue(Decode&& decode, std::string& error) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buf) != 0) {
      if (errno == EAGAIN) return true;
      error = errno == ENODEV ? "the device was unplugged" : "VIDIOC_DQBUF failed (" + errno_text() + ")";
      return false;
    }
    const double stamp_s = double(buf.timestamp.tv_sec) + 1e-6 * double(buf.timestamp.tv_usec);
    if (buf.index < buffers_.size() && !(buf.flags & V4L2_BUF_FLAG_ERROR)) {
      const auto* data = static_cast<const std::uint8_t*>(buffers_[buf.index].first);
      try {
        decode(stamp_s, data, std::min<size_t>(buf.bytesused, buffers_[buf.index].second));
      } catch (const Error&) {
        // A corrupt frame (a truncated MJPEG transfer): skipped, the stream goes on.
      }
    }
    if (xioctl(fd_, VIDIOC_QBUF, &buf) != 0) {
      error = "VIDIOC_QBUF failed (" + errno_text() + ")";
      return false;
    }
    return true;
  }

  DepthImage depth(const std::uint8_t* data, size_t bytes, double unit_m) const {
    return decode_z16(data, bytes, width_, height_, stride_, unit_m);
  }
  ColorImage color(const std::uint8_t* data, size_t bytes) const {
    return decode_color(format_, data, bytes, width_, height_, format_ == PixelFormat::mjpeg ? 0 : stride_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw Error("v4l2://" + path_ + ": " + what); }
  static std::string errno_text() { return std::strerror(errno); }

  void map_buffers() {
    v4l2_requestbuffers req{};
    req.count = 4;
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_REQBUFS, &req) != 0 || req.count < 2)
      fail("no memory-mapped streaming buffers (" + errno_text() + ")");
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer buf{};
      buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      buf.memory = V4L2_MEMORY_MMAP;
      buf.index = i;
      if (xioctl(fd_, VIDIOC_QUERYBUF, &buf) != 0) fail("VIDIOC_QUERYBUF failed (" + errno_text() + ")");
      void* p = ::mmap(nullptr, buf.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buf.m.offset);
      buffers_.emplace_back(p, buf.length);
      if (p == MAP_FAILED) fail("mmap failed (" + errno_text() + ")");
      if (xioctl(fd_, VIDIOC_QBUF, &buf) != 0) fail("VIDIOC_QBUF failed (" + errno_text() + ")");
    }
  }

  std::string path_, card_;
  int fd_ = -1;
  PixelFormat format_ = PixelFormat::yuyv;
  int width_ = 0, height_ = 0;
  size_t stride_ = 0;
  std::vector<std::pair<void*, size_t>> buffers_;
  bool streaming_ = false;
};

class V4l2Capture : public CaptureDevice {
 public:
  V4l2Capture(const std::vector<std::string>& paths, const LiveInputOptions& o)
      : options_(o), pairer_(o.max_pair_difference_s) {
    if (paths.empty() || paths.size() > 2)
      throw Error("v4l2://: expected one node or two joined by '+' (v4l2:///dev/video0+/dev/video2)");
    for (const auto& p : paths) nodes_.push_back(std::make_unique<V4l2Node>(p, o));
    if (nodes_.size() == 2 && nodes_[0]->is_depth() == nodes_[1]->is_depth())
      throw Error("v4l2://" + paths[0] + "+" + paths[1] + ": two nodes pair one colour with one depth node; both are " +
                  (nodes_[0]->is_depth() ? "depth (Z16)" : "colour"));
    name_ = "V4L2 " + nodes_[0]->describe() + (nodes_.size() == 2 ? " + " + nodes_[1]->describe() : "");
    camera_ = choose_live_camera(o.camera, std::nullopt, "", o.width, o.height);
    if (nodes_.size() == 2) camera_.origin += "; depth and colour nodes paired by time stamp, not registered";
  }

  CaptureResult grab(std::chrono::milliseconds timeout) override {
    CaptureResult r;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return r;
      pollfd fds[2]{};
      for (size_t i = 0; i < nodes_.size(); ++i) fds[i] = {nodes_[i]->fd(), POLLIN, 0};
      const int n = ::poll(fds, nodes_t(), int(left.count()));
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) return failed(std::string("poll failed (") + std::strerror(errno) + ")");
      if (n == 0) return r;
      for (size_t i = 0; i < nodes_.size(); ++i) {
        if (fds[i].revents & (POLLERR | POLLHUP | POLLNVAL)) return failed("the device stopped (unplugged?)");
        if (!(fds[i].revents & POLLIN)) continue;
        V4l2Node& node = *nodes_[i];
        std::string error;
        std::optional<CapturedFrame> single;
        const bool alive = node.dequeue(
            [&](double stamp_s, const std::uint8_t* data, size_t bytes) {
              if (nodes_.size() == 1) {
                CapturedFrame f;
                f.timestamp_s = stamp_s;
                if (node.is_depth()) {
                  f.depth = node.depth(data, bytes, options_.z16_unit_m);
                  f.color = ColorImage(node.width(), node.height());
                } else {
                  f.color = node.color(data, bytes);
                  f.depth = DepthImage(node.width(), node.height());
                }
                single = std::move(f);
              } else if (node.is_depth()) {
                pairer_.offer_depth(stamp_s, node.depth(data, bytes, options_.z16_unit_m));
              } else {
                pairer_.offer_color(stamp_s, node.color(data, bytes));
              }
            },
            error);
        if (!alive) return failed(node.path() + ": " + error);
        if (single) return capture_frame(std::move(*single));
        if (auto pair = pairer_.take()) return capture_frame(std::move(*pair));
      }
    }
  }

  const PinholeCamera& camera() const override { return camera_.camera; }
  const std::string& camera_origin() const override { return camera_.origin; }
  const std::string& name() const override { return name_; }

 private:
  nfds_t nodes_t() const { return nfds_t(nodes_.size()); }
  CaptureResult failed(const std::string& what) const { return capture_failed(name_, what); }

  LiveInputOptions options_;
  StampPairer pairer_;
  std::vector<std::unique_ptr<V4l2Node>> nodes_;
  std::string name_;
  CameraChoice camera_;
};

}  // namespace

std::vector<std::string> parse_v4l2_nodes(const std::string& spec) {
  std::vector<std::string> nodes;
  size_t start = 0;
  for (;;) {
    const size_t plus = spec.find('+', start);
    nodes.push_back(spec.substr(start, plus == std::string::npos ? std::string::npos : plus - start));
    if (plus == std::string::npos) break;
    start = plus + 1;
  }
  for (const auto& n : nodes)
    if (n.empty() || n[0] != '/')
      throw Error("v4l2://" + spec + ": expected absolute node paths (v4l2:///dev/video0, or two joined by '+')");
  return nodes;
}

std::unique_ptr<CaptureDevice> open_v4l2(const std::vector<std::string>& nodes, const LiveInputOptions& options) {
  return std::make_unique<V4l2Capture>(nodes, options);
}

DeviceListing list_v4l2_devices() {
  DeviceListing listing;
  listing.backend = "v4l2";
  std::vector<std::string> paths;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator("/dev", ec))
    if (e.path().filename().string().rfind("video", 0) == 0) paths.push_back(e.path().string());
  std::sort(paths.begin(), paths.end());
  for (const auto& p : paths) {
    const int fd = ::open(p.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      listing.devices.push_back("v4l2://" + p + "  cannot open (" + std::strerror(errno) + ")");
      continue;
    }
    v4l2_capability cap{};
    if (xioctl(fd, VIDIOC_QUERYCAP, &cap) == 0) {
      const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
      if (caps & V4L2_CAP_VIDEO_CAPTURE)
        listing.devices.push_back("v4l2://" + p + "  " + reinterpret_cast<const char*>(cap.card) + ": " +
                                  formats_text(node_formats(fd)));
    }
    ::close(fd);
  }
  if (listing.devices.empty()) listing.note = "none connected (no capture node under /dev/video*)";
  return listing;
}

}  // namespace hf
