// Device copies of host images: on --backend opencl the frame pyramid and the model maps stay on the device between
// stages (issue 20), and the host images are their read-back mirrors. The stage that made an image on a device
// publishes the device buffer as that image's copy (core/opencl/opencl_context.h, Context::publish) and
// gets a token; the holder of the image keeps the token beside it (FramePyramidLevel::device_copies,
// fusion::RaycastResult::device_copies). While the token lives, a later stage on the same device binds the copy
// instead of uploading the host pixels (the reduction backend, the model pyramid).
//
// The rule that keeps a copy true: a token lives no longer than the pixels it mirrors stay as they are, at their
// address. Whoever writes such an image in place, or frees or replaces it while keeping the holder, drops its
// copy first (drop(), clear()); an image moved to another holder takes its copy along (move_to()). Copying a holder
// copies no tokens (the copied images live elsewhere), so a copy cannot keep a freed image's entry alive. No OpenCL
// here: the token is opaque.
#pragma once

#include <cstddef>
#include <memory>
#include <utility>
#include <vector>

namespace hf {

struct DeviceCopy {
  const void* host = nullptr;          // the first host pixel the copy mirrors
  std::shared_ptr<const void> token;   // keeps the copy published and its device buffer alive
};

class DeviceCopies {
 public:
  DeviceCopies() = default;
  DeviceCopies(const DeviceCopies&) {}  // a copied holder's images are new: none of these tokens is theirs
  DeviceCopies& operator=(const DeviceCopies&) {
    copies_.clear();  // the holder's images were overwritten by copies
    return *this;
  }
  DeviceCopies(DeviceCopies&&) noexcept = default;
  DeviceCopies& operator=(DeviceCopies&&) noexcept = default;

  void add(const void* host, std::shared_ptr<const void> token) {
    if (host != nullptr && token != nullptr) copies_.push_back({host, std::move(token)});
  }
  // Drops the copy of the image at `host`: before that image is written in place or replaced.
  void drop(const void* host) {
    std::erase_if(copies_, [host](const DeviceCopy& c) { return c.host == host; });
  }
  // Moves the copy of the image at `host` (if held) to `to`: for an image moved to another holder, whose pixels
  // keep their address.
  void move_to(DeviceCopies& to, const void* host) {
    for (auto it = copies_.begin(); it != copies_.end(); ++it) {
      if (it->host == host) {
        to.copies_.push_back(std::move(*it));
        copies_.erase(it);
        return;
      }
    }
  }
  void clear() { copies_.clear(); }
  bool empty() const { return copies_.empty(); }
  std::size_t size() const { return copies_.size(); }

 private:
  std::vector<DeviceCopy> copies_;
};

}  // namespace hf
