#include "io/openni2_capture.h"

#include <OpenNI.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "core/error.h"
#include "core/regular_path.h"
#include "io/dataset.h"
#include "io/frame_pairing.h"
#include "io/pixel_formats.h"

namespace hf {
namespace {

namespace ni = openni;

std::string extended_error() {
  std::string e = ni::OpenNI::getExtendedError();
  while (!e.empty() && (e.back() == '\n' || e.back() == ' ' || e.back() == '\t')) e.pop_back();
  for (char& c : e)
    if (c == '\n' || c == '\t') c = ' ';
  e.erase(0, e.find_first_not_of(' '));
  return e.empty() ? "no detail from OpenNI2" : e;
}

// OpenNI2 is initialised once per process and never shut down: shutdown() unloads the driver modules, and the
// drivers keep allocations they only free at unload (LeakSanitizer then reports them from unloaded code that no
// suppression can name). Initialising again after a failure retries.
class OpenNiContext {
 public:
  OpenNiContext() {
    static std::mutex mutex;
    static bool initialised = false;
    std::lock_guard<std::mutex> lock(mutex);
    if (initialised) return;
    if (ni::OpenNI::initialize() != ni::STATUS_OK)
      throw Error("OpenNI2: cannot initialise (" + extended_error() + ")");
    initialised = true;
  }
};

std::string format_name(ni::PixelFormat f) {
  switch (f) {
    case ni::PIXEL_FORMAT_DEPTH_1_MM: return "depth 1 mm";
    case ni::PIXEL_FORMAT_DEPTH_100_UM: return "depth 100 um";
    case ni::PIXEL_FORMAT_SHIFT_9_2: return "shift 9.2";
    case ni::PIXEL_FORMAT_SHIFT_9_3: return "shift 9.3";
    case ni::PIXEL_FORMAT_RGB888: return "rgb888";
    case ni::PIXEL_FORMAT_YUV422: return "yuv422";
    case ni::PIXEL_FORMAT_GRAY8: return "gray8";
    case ni::PIXEL_FORMAT_GRAY16: return "gray16";
    case ni::PIXEL_FORMAT_JPEG: return "jpeg";
    case ni::PIXEL_FORMAT_YUYV: return "yuyv";
  }
  return "format " + std::to_string(int(f));
}

std::string mode_text(const ni::VideoMode& m) {
  return std::to_string(m.getResolutionX()) + "x" + std::to_string(m.getResolutionY()) + "@" +
         std::to_string(m.getFps()) + " " + format_name(m.getPixelFormat());
}

bool usable_depth(ni::PixelFormat f) { return f == ni::PIXEL_FORMAT_DEPTH_1_MM || f == ni::PIXEL_FORMAT_DEPTH_100_UM; }
std::optional<PixelFormat> color_format(ni::PixelFormat f) {
  switch (f) {
    case ni::PIXEL_FORMAT_RGB888: return PixelFormat::rgb24;
    case ni::PIXEL_FORMAT_YUV422: return PixelFormat::uyvy;  // OniYUV422DoublePixel: u, y1, v, y2
    case ni::PIXEL_FORMAT_YUYV: return PixelFormat::yuyv;
    case ni::PIXEL_FORMAT_JPEG: return PixelFormat::mjpeg;
    default: return std::nullopt;
  }
}

std::string sensor_modes(const ni::SensorInfo* info) {
  if (!info) return "none";
  std::string s;
  const ni::Array<ni::VideoMode>& modes = info->getSupportedVideoModes();
  for (int i = 0; i < modes.getSize(); ++i) s += (s.empty() ? "" : ", ") + mode_text(modes[i]);
  return s.empty() ? "none" : s;
}

// The mode of `info` at width x height whose rate is nearest `fps`, preferring formats earlier in `ok`.
std::optional<ni::VideoMode> pick_mode(const ni::SensorInfo* info, int width, int height, int fps, bool depth) {
  if (!info) return std::nullopt;
  const ni::Array<ni::VideoMode>& modes = info->getSupportedVideoModes();
  std::optional<ni::VideoMode> best;
  auto rank = [&](const ni::VideoMode& m) {
    const ni::PixelFormat f = m.getPixelFormat();
    const int format_rank = depth ? (f == ni::PIXEL_FORMAT_DEPTH_1_MM ? 0 : 1)
                                  : (f == ni::PIXEL_FORMAT_RGB888 ? 0 : f == ni::PIXEL_FORMAT_JPEG ? 2 : 1);
    return std::abs(m.getFps() - fps) * 10 + format_rank;
  };
  for (int i = 0; i < modes.getSize(); ++i) {
    const ni::VideoMode& m = modes[i];
    if (m.getResolutionX() != width || m.getResolutionY() != height) continue;
    if (depth ? !usable_depth(m.getPixelFormat()) : !color_format(m.getPixelFormat())) continue;
    if (!best || rank(m) < rank(*best)) best = m;
  }
  return best;
}

std::string device_list_text() {
  ni::Array<ni::DeviceInfo> list;
  ni::OpenNI::enumerateDevices(&list);
  std::string s;
  for (int i = 0; i < list.getSize(); ++i)
    s += (s.empty() ? "" : ", ") + std::string("openni2://") + list[i].getUri() + " (" + list[i].getVendor() + " " +
         list[i].getName() + ")";
  return s.empty() ? "none" : s;
}

class Disconnected : public ni::OpenNI::DeviceDisconnectedListener {
 public:
  explicit Disconnected(std::string uri) : uri_(std::move(uri)) {}
  void onDeviceDisconnected(const ni::DeviceInfo* info) override {
    if (info && uri_ == info->getUri()) gone.store(true);
  }
  std::atomic<bool> gone{false};

 private:
  std::string uri_;
};

class OpenNi2Capture : public CaptureDevice {
 public:
  OpenNi2Capture(const std::string& uri, const LiveInputOptions& options)
      : options_(options), pairer_(options.max_pair_difference_s) {
    const bool file = uri.size() > 4 && uri.compare(uri.size() - 4, 4, ".oni") == 0;
    asked_ = file ? uri : "openni2://" + uri;
    if (file) {
      // OpenNI2's file driver would block on a FIFO and fail obscurely on a folder or device: say what it is.
      std::error_code ec;
      if (!std::filesystem::exists(uri, ec)) throw Error(uri + ": no such recording (.oni file)");
      require_regular_path(uri, "recording (.oni file)");
    }
    if (device_.open(uri.empty() ? ni::ANY_DEVICE : uri.c_str()) != ni::STATUS_OK) {
      const std::string error = extended_error();
      throw Error(asked_ + ": cannot open (" + error + "); OpenNI2 sees: " + device_list_text());
    }
    const ni::DeviceInfo& info = device_.getDeviceInfo();
    uri_ = info.getUri();
    name_ = std::string("OpenNI2 ") + (device_.isFile() ? "recording" : "'" + std::string(info.getVendor()) + " " +
                                                                           info.getName() + "'") +
            " (" + (device_.isFile() ? uri_ : "openni2://" + uri_) + ")";
    if (!device_.hasSensor(ni::SENSOR_DEPTH) || !device_.hasSensor(ni::SENSOR_COLOR))
      throw Error(asked_ + ": needs a depth and a colour sensor; it has " +
                  (device_.hasSensor(ni::SENSOR_DEPTH) ? "depth" : "no depth") + " and " +
                  (device_.hasSensor(ni::SENSOR_COLOR) ? "colour" : "no colour"));
    if (depth_.create(device_, ni::SENSOR_DEPTH) != ni::STATUS_OK ||
        color_.create(device_, ni::SENSOR_COLOR) != ni::STATUS_OK)
      throw Error(asked_ + ": cannot create the depth and colour streams (" + extended_error() + ")");
    if (device_.isFile()) {
      ni::PlaybackControl* playback = device_.getPlaybackControl();
      if (playback) {
        playback->setRepeatEnabled(false);
        playback->setSpeed(1.0f);  // the recorded rate: a recording behaves as its device did
        const int n = playback->getNumberOfFrames(depth_);
        if (n > 0) frames_ = size_t(n);
      }
    } else {
      configure_modes();
    }
    const ni::VideoMode dm = depth_.getVideoMode(), cm = color_.getVideoMode();
    if (!usable_depth(dm.getPixelFormat()) || !color_format(cm.getPixelFormat()))
      throw Error(asked_ + ": unsupported modes depth " + mode_text(dm) + ", colour " + mode_text(cm) +
                  " (hashfusion reads depth 1 mm / 100 um and colour rgb888 / yuv422 / yuyv / jpeg)");
    if (dm.getResolutionX() != cm.getResolutionX() || dm.getResolutionY() != cm.getResolutionY())
      throw Error(asked_ + ": depth " + mode_text(dm) + " and colour " + mode_text(cm) + " differ in size");
    width_ = dm.getResolutionX();
    height_ = dm.getResolutionY();
    depth_unit_m_ = dm.getPixelFormat() == ni::PIXEL_FORMAT_DEPTH_1_MM ? 1e-3 : 1e-4;

    std::string registration = "depth as recorded";
    if (!device_.isFile()) {
      if (device_.isImageRegistrationModeSupported(ni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) &&
          device_.setImageRegistrationMode(ni::IMAGE_REGISTRATION_DEPTH_TO_COLOR) == ni::STATUS_OK)
        registration = "depth registered to colour by the device";
      else
        registration = "depth NOT registered to colour (the device cannot)";
      device_.setDepthColorSyncEnabled(true);  // best effort: pairing by stamp does not rely on it
      for (ni::VideoStream* s : {&depth_, &color_})
        if (s->isPropertySupported(ni::STREAM_PROPERTY_MIRRORING)) s->setMirroringEnabled(false);
    }
    choose_camera(registration);
    if (depth_.start() != ni::STATUS_OK || color_.start() != ni::STATUS_OK)
      throw Error(asked_ + ": cannot start streaming (" + extended_error() + ")");
    disconnected_ = std::make_unique<Disconnected>(uri_);
    ni::OpenNI::addDeviceDisconnectedListener(disconnected_.get());
  }

  ~OpenNi2Capture() override {
    if (disconnected_) ni::OpenNI::removeDeviceDisconnectedListener(disconnected_.get());
    depth_.stop();
    color_.stop();
    // Some drivers (OpenNI2's own Dummy device among them) end their frame threads by polling a flag once per
    // frame period without joining them; two periods at 30 Hz keep destroy() from freeing a stream still in use.
    std::this_thread::sleep_for(std::chrono::milliseconds(70));
    depth_.destroy();
    color_.destroy();
    device_.close();
  }

  CaptureResult grab(std::chrono::milliseconds timeout) override {
    CaptureResult r;
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    for (;;) {
      if (disconnected_->gone.load()) return failed("the device was disconnected");
      if (frames_ && depth_read_ >= *frames_ && !pairer_.holds_depth()) {
        r.status = CaptureStatus::end;
        return r;
      }
      const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline -
                                                                              std::chrono::steady_clock::now());
      if (left.count() <= 0) return r;  // timeout
      ni::VideoStream* streams[2] = {&depth_, &color_};
      int ready = -1;
      const ni::Status s = ni::OpenNI::waitForAnyStream(streams, 2, &ready, int(left.count()));
      if (s == ni::STATUS_TIME_OUT) {
        // A recording whose last depth frame found no colour partner has nothing more to give.
        if (frames_ && depth_read_ >= *frames_) r.status = CaptureStatus::end;
        return r;
      }
      if (s != ni::STATUS_OK || ready < 0 || ready > 1)
        return failed("waiting for frames failed (" + extended_error() + ")");
      ni::VideoFrameRef frame;
      if (streams[ready]->readFrame(&frame) != ni::STATUS_OK || !frame.isValid())
        return failed("reading a frame failed (" + extended_error() + ")");
      try {
        const double stamp_s = double(frame.getTimestamp()) * 1e-6;  // OpenNI2 stamps are microseconds
        if (ready == 0) {
          ++depth_read_;
          pairer_.offer_depth(stamp_s, convert_depth(frame));
        } else {
          pairer_.offer_color(stamp_s, convert_color(frame));
        }
      } catch (const Error& e) {
        return failed(e.what());
      }
      if (auto pair = pairer_.take()) return capture_frame(std::move(*pair));
    }
  }

  const PinholeCamera& camera() const override { return camera_.camera; }
  const std::string& camera_origin() const override { return camera_.origin; }
  const std::string& name() const override { return name_; }
  std::optional<size_t> frame_count() const override { return frames_; }

 private:
  CaptureResult failed(const std::string& what) const { return capture_failed(name_, what); }

  void configure_modes() {
    const ni::SensorInfo* di = device_.getSensorInfo(ni::SENSOR_DEPTH);
    const ni::SensorInfo* ci = device_.getSensorInfo(ni::SENSOR_COLOR);
    const auto dm = pick_mode(di, options_.width, options_.height, options_.fps, true);
    const auto cm = pick_mode(ci, options_.width, options_.height, options_.fps, false);
    const std::string wanted = std::to_string(options_.width) + "x" + std::to_string(options_.height);
    // Devices whose mode list is empty (some drivers report none) keep their current modes, checked below.
    if (di && di->getSupportedVideoModes().getSize() > 0 && !dm)
      throw Error(asked_ + ": no depth mode at " + wanted + "; the device has " + sensor_modes(di));
    if (ci && ci->getSupportedVideoModes().getSize() > 0 && !cm)
      throw Error(asked_ + ": no colour mode at " + wanted + "; the device has " + sensor_modes(ci));
    set_mode(depth_, dm, "depth");
    set_mode(color_, cm, "colour");
  }

  // Drivers with a single fixed mode may refuse to "change" to it, so a mode already in force is not set.
  void set_mode(ni::VideoStream& stream, const std::optional<ni::VideoMode>& mode, const char* what) {
    if (!mode) return;
    const ni::VideoMode now = stream.getVideoMode();
    if (mode_text(now) == mode_text(*mode)) return;
    if (stream.setVideoMode(*mode) != ni::STATUS_OK)
      throw Error(asked_ + ": cannot set " + what + " mode " + mode_text(*mode) + " (" + extended_error() + ")");
  }

  void choose_camera(const std::string& registration) {
    std::optional<PinholeCamera> device_camera;
    const float hfov = color_.getHorizontalFieldOfView(), vfov = color_.getVerticalFieldOfView();
    if (std::isfinite(hfov) && std::isfinite(vfov) && hfov > 0.1f && hfov < 3.0f && vfov > 0.1f && vfov < 3.0f) {
      PinholeCamera c;
      c.width = width_;
      c.height = height_;
      c.fx = width_ / (2.0 * std::tan(double(hfov) / 2.0));
      c.fy = height_ / (2.0 * std::tan(double(vfov) / 2.0));
      c.cx = (width_ - 1) / 2.0;
      c.cy = (height_ - 1) / 2.0;
      device_camera = c;
    }
    camera_ = choose_live_camera(options_.camera, device_camera, "the device's fields of view", width_, height_);
    camera_.origin += "; " + registration;
  }

  // OpenNI2 depth pixels are 16-bit little-endian units, the layout of V4L2's Z16.
  DepthImage convert_depth(const ni::VideoFrameRef& f) const {
    check_size(f, "depth");
    return decode_z16(static_cast<const std::uint8_t*>(f.getData()), size_t(f.getDataSize()), width_, height_,
                      size_t(f.getStrideInBytes()), depth_unit_m_);
  }

  ColorImage convert_color(const ni::VideoFrameRef& f) const {
    check_size(f, "colour");
    const PixelFormat format = *color_format(f.getVideoMode().getPixelFormat());
    return decode_color(format, static_cast<const std::uint8_t*>(f.getData()), size_t(f.getDataSize()), width_,
                        height_, format == PixelFormat::mjpeg ? 0 : size_t(f.getStrideInBytes()));
  }

  void check_size(const ni::VideoFrameRef& f, const char* what) const {
    if (f.getWidth() != width_ || f.getHeight() != height_)
      throw Error(std::string(what) + " frame is " + std::to_string(f.getWidth()) + "x" +
                  std::to_string(f.getHeight()) + ", the stream " + std::to_string(width_) + "x" +
                  std::to_string(height_));
  }

  LiveInputOptions options_;
  StampPairer pairer_;
  OpenNiContext context_;
  ni::Device device_;
  ni::VideoStream depth_, color_;
  std::string asked_, uri_, name_;
  CameraChoice camera_;
  int width_ = 0, height_ = 0;
  double depth_unit_m_ = 1e-3;
  std::optional<size_t> frames_;
  size_t depth_read_ = 0;
  std::unique_ptr<Disconnected> disconnected_;
};

}  // namespace

std::unique_ptr<CaptureDevice> open_openni2(const std::string& uri, const LiveInputOptions& options) {
  return std::make_unique<OpenNi2Capture>(uri, options);
}

DeviceListing list_openni2_devices() {
  DeviceListing listing;
  listing.backend = "openni2";
  try {
    OpenNiContext context;
    ni::Array<ni::DeviceInfo> list;
    ni::OpenNI::enumerateDevices(&list);
    for (int i = 0; i < list.getSize(); ++i) {
      std::string line = std::string("openni2://") + list[i].getUri() + "  " + list[i].getVendor() + " " +
                         list[i].getName();
      ni::Device device;
      if (device.open(list[i].getUri()) == ni::STATUS_OK) {
        line += ": depth " + sensor_modes(device.getSensorInfo(ni::SENSOR_DEPTH)) + "; colour " +
                sensor_modes(device.getSensorInfo(ni::SENSOR_COLOR));
        device.close();
      } else {
        line += ": cannot open (" + extended_error() + ")";
      }
      listing.devices.push_back(line);
    }
    if (listing.devices.empty()) listing.note = "none connected";
  } catch (const Error& e) {
    listing.note = e.what();
  }
  return listing;
}

}  // namespace hf
