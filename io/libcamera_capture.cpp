#include "io/libcamera_capture.h"

#include <sys/mman.h>

#include <cstdlib>

#include <condition_variable>
#include <deque>
#include <libcamera/libcamera.h>
#include <mutex>

#include "core/error.h"
#include "io/dataset.h"

namespace hf {
namespace {

namespace lc = libcamera;

// libcamera logs INFO and WARN lines to stderr by default; hashfusion's own messages say what matters.
// Categories made later keep the default level, so the environment variable libcamera reads at start-up is set
// too (unless the user set it).
void quiet_libcamera() {
  ::setenv("LIBCAMERA_LOG_LEVELS", "*:ERROR", 0);
  lc::logSetLevel("*", "ERROR");
}

std::string camera_ids(lc::CameraManager& manager) {
  std::string s;
  for (const auto& c : manager.cameras()) s += (s.empty() ? "" : ", ") + std::string("libcamera://") + c->id();
  return s.empty() ? "none" : s;
}

// A completed request's planes, mapped for reading. Planes of one dma-buf share a mapping.
class MappedBuffer {
 public:
  explicit MappedBuffer(const lc::FrameBuffer& buffer) {
    for (const lc::FrameBuffer::Plane& plane : buffer.planes()) {
      const int fd = plane.fd.get();
      const size_t end = size_t(plane.offset) + plane.length;
      void* base = ::mmap(nullptr, end, PROT_READ, MAP_SHARED, fd, 0);
      if (base == MAP_FAILED) throw Error("libcamera frame: cannot map a plane");
      maps_.emplace_back(base, end);
      planes_.push_back({static_cast<const std::uint8_t*>(base) + plane.offset, plane.length});
    }
  }
  ~MappedBuffer() {
    for (auto& m : maps_) ::munmap(m.first, m.second);
  }
  MappedBuffer(const MappedBuffer&) = delete;
  MappedBuffer& operator=(const MappedBuffer&) = delete;
  const std::vector<PlaneView>& planes() const { return planes_; }

 private:
  std::vector<std::pair<void*, size_t>> maps_;
  std::vector<PlaneView> planes_;
};

class LibcameraCapture : public CaptureDevice {
 public:
  LibcameraCapture(const std::string& id, const LiveInputOptions& o) : options_(o) {
    quiet_libcamera();
    manager_ = std::make_unique<lc::CameraManager>();
    if (manager_->start() != 0) throw Error("libcamera://" + id + ": the camera manager does not start");
    camera_ = id.empty() ? (manager_->cameras().empty() ? nullptr : manager_->cameras().front()) : manager_->get(id);
    if (!camera_) throw Error("libcamera://" + id + ": no such camera; libcamera sees: " + camera_ids(*manager_));
    if (camera_->acquire() != 0) throw Error("libcamera://" + camera_->id() + ": in use by another process");
    acquired_ = true;
    config_ = camera_->generateConfiguration({lc::StreamRole::VideoRecording});
    if (!config_ || config_->empty()) throw Error("libcamera://" + camera_->id() + ": no video stream");
    lc::StreamConfiguration& sc = config_->at(0);
    static const lc::PixelFormat kPreference[] = {lc::formats::YUYV,     lc::formats::BGR888,  lc::formats::RGB888,
                                                  lc::formats::XRGB8888, lc::formats::XBGR8888, lc::formats::NV12,
                                                  lc::formats::MJPEG};
    const std::vector<lc::PixelFormat> offered = sc.formats().pixelformats();
    std::string offered_text;
    for (const auto& f : offered) offered_text += (offered_text.empty() ? "" : ", ") + f.toString();
    bool found = false;
    for (const auto& want : kPreference)
      if (std::find(offered.begin(), offered.end(), want) != offered.end()) {
        sc.pixelFormat = want;
        found = true;
        break;
      }
    if (!found)
      throw Error("libcamera://" + camera_->id() + ": no format hashfusion reads; it offers " +
                  (offered_text.empty() ? "none" : offered_text));
    sc.size = lc::Size(unsigned(o.width), unsigned(o.height));
    sc.bufferCount = 4;
    if (config_->validate() == lc::CameraConfiguration::Invalid || int(sc.size.width) != o.width ||
        int(sc.size.height) != o.height)
      throw Error("libcamera://" + camera_->id() + ": no " + std::to_string(o.width) + "x" + std::to_string(o.height) +
                  " mode (it adjusts to " + sc.size.toString() + " " + sc.pixelFormat.toString() + ")");
    if (camera_->configure(config_.get()) != 0)
      throw Error("libcamera://" + camera_->id() + ": configuration refused");
    stream_ = sc.stream();
    fourcc_ = sc.pixelFormat.fourcc();
    stride_ = sc.stride;
    allocator_ = std::make_unique<lc::FrameBufferAllocator>(camera_);
    if (allocator_->allocate(stream_) < 0) throw Error("libcamera://" + camera_->id() + ": cannot allocate buffers");
    for (const auto& buffer : allocator_->buffers(stream_)) {
      std::unique_ptr<lc::Request> request = camera_->createRequest();
      if (!request || request->addBuffer(stream_, buffer.get()) != 0)
        throw Error("libcamera://" + camera_->id() + ": cannot create requests");
      requests_.push_back(std::move(request));
    }
    camera_->requestCompleted.connect(this, &LibcameraCapture::completed);
    camera_->disconnected.connect(this, &LibcameraCapture::gone);
    name_ = "libcamera '" + camera_->id() + "' (" + sc.toString() + ")";
    camera_choice_ = choose_live_camera(o.camera, std::nullopt, "", o.width, o.height);
    camera_choice_.origin += "; colour only (no depth sensor)";
    if (camera_->start() != 0) throw Error("libcamera://" + camera_->id() + ": cannot start");
    started_ = true;
    for (auto& r : requests_) camera_->queueRequest(r.get());
  }

  ~LibcameraCapture() override {
    if (started_) camera_->stop();  // completes (cancels) every queued request before returning
    if (camera_) {
      camera_->requestCompleted.disconnect(this);
      camera_->disconnected.disconnect(this);
    }
    requests_.clear();
    if (allocator_ && stream_) allocator_->free(stream_);
    allocator_.reset();
    if (acquired_) camera_->release();
    camera_.reset();
    if (manager_) manager_->stop();
  }

  CaptureResult grab(std::chrono::milliseconds timeout) override {
    CaptureResult r;
    std::unique_lock<std::mutex> lock(mutex_);
    if (!ready_.wait_for(lock, timeout, [this] { return !done_.empty() || disconnected_; })) return r;
    if (disconnected_) {
      r.status = CaptureStatus::failed;
      r.message = name_ + ": the camera was disconnected";
      return r;
    }
    lc::Request* request = done_.front();
    done_.pop_front();
    lock.unlock();
    if (request->status() == lc::Request::RequestComplete) {
      const lc::FrameBuffer* buffer = request->findBuffer(stream_);
      try {
        const MappedBuffer mapped(*buffer);
        r.frame.color = libcamera_planes_to_rgb(fourcc_, mapped.planes(), options_.width, options_.height, stride_);
        r.frame.depth = DepthImage(options_.width, options_.height);
        r.frame.timestamp_s = double(buffer->metadata().timestamp) * 1e-9;
        r.status = CaptureStatus::frame;
      } catch (const Error&) {
        // A frame that does not decode is skipped; the next request follows.
      }
    }
    request->reuse(lc::Request::ReuseBuffers);
    camera_->queueRequest(request);
    return r;
  }

  const PinholeCamera& camera() const override { return camera_choice_.camera; }
  const std::string& camera_origin() const override { return camera_choice_.origin; }
  const std::string& name() const override { return name_; }

 private:
  // libcamera's own thread.
  void completed(lc::Request* request) {
    if (request->status() == lc::Request::RequestCancelled) return;
    std::lock_guard<std::mutex> lock(mutex_);
    done_.push_back(request);
    ready_.notify_one();
  }
  void gone() {
    std::lock_guard<std::mutex> lock(mutex_);
    disconnected_ = true;
    ready_.notify_one();
  }

  LiveInputOptions options_;
  std::unique_ptr<lc::CameraManager> manager_;
  std::shared_ptr<lc::Camera> camera_;
  std::unique_ptr<lc::CameraConfiguration> config_;
  std::unique_ptr<lc::FrameBufferAllocator> allocator_;
  std::vector<std::unique_ptr<lc::Request>> requests_;
  lc::Stream* stream_ = nullptr;
  std::uint32_t fourcc_ = 0;
  size_t stride_ = 0;
  bool acquired_ = false, started_ = false;
  std::string name_;
  CameraChoice camera_choice_;
  std::mutex mutex_;
  std::condition_variable ready_;
  std::deque<lc::Request*> done_;
  bool disconnected_ = false;
};

}  // namespace

std::unique_ptr<CaptureDevice> open_libcamera(const std::string& id, const LiveInputOptions& options) {
  return std::make_unique<LibcameraCapture>(id, options);
}

DeviceListing list_libcamera_devices() {
  DeviceListing listing;
  listing.backend = "libcamera";
  quiet_libcamera();
  lc::CameraManager manager;
  if (manager.start() != 0) {
    listing.note = "the camera manager does not start";
    return listing;
  }
  for (const auto& c : manager.cameras()) {
    std::string line = "libcamera://" + c->id();
    if (auto config = c->generateConfiguration({lc::StreamRole::VideoRecording}); config && !config->empty()) {
      const lc::StreamFormats& formats = config->at(0).formats();
      std::string modes;
      for (const auto& f : formats.pixelformats()) {
        modes += (modes.empty() ? "" : ", ") + f.toString();
        const auto sizes = formats.sizes(f);
        if (!sizes.empty()) modes += " " + sizes.front().toString() + ".." + sizes.back().toString();
      }
      line += ": " + modes;
    }
    listing.devices.push_back(line);
  }
  manager.stop();
  if (listing.devices.empty()) listing.note = "none connected";
  return listing;
}

}  // namespace hf
