// One OpenCL device, its context and in-order queue, and the programs built on it.
//
//   auto ctx = hf::opencl::Context::shared();          // chosen once (see below), shared while anyone holds it
//   cl::Program p = ctx->program("registration", hf::opencl::registration_program_source(), "-DHF_X=1");
//   cl::Kernel k(p, "hf_reduce_rows");
//
// Device choice, first that applies:
//   1. the HF_OPENCL_DEVICE environment variable (or the `device_spec` argument when non-empty):
//        "P:D"   platform index P, device index D (as listed by `clinfo -l`),
//        "gpu" / "cpu" / "accelerator"   the first device of that type,
//        TEXT    the first device whose "platform / device" name contains TEXT (case-insensitive);
//      a spec that matches nothing is an hf::Error listing the devices;
//   2. the first GPU of any platform;
//   3. the first device of any type.
// With no OpenCL platform (no ICD installed) construction throws hf::Error
// "no OpenCL platform found: install pocl-opencl-icd or use --backend cpu".
//
// Programs are built once per context and cached by key; a failed build throws hf::Error whose message carries
// the driver's build log. OpenCL errors from the C++ bindings are reported as hf::Error naming the call and the
// error code (e.g. "clEnqueueNDRangeKernel: CL_OUT_OF_RESOURCES (-5)").
//
// Thread-safety: program() and the accessors may be called concurrently; the queue is in-order and shared, so
// callers that enqueue from several threads must serialise their own command sequences (the backends do, with
// their own mutex).
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

// The bindings' version macros must agree in every translation unit: they are set by CMake on
// hf_registration_opencl (PUBLIC), these are only the fallback for a stray include.
#ifndef CL_HPP_TARGET_OPENCL_VERSION
#define CL_HPP_TARGET_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_MINIMUM_OPENCL_VERSION
#define CL_HPP_MINIMUM_OPENCL_VERSION 120
#endif
#ifndef CL_HPP_ENABLE_EXCEPTIONS
#define CL_HPP_ENABLE_EXCEPTIONS
#endif
#include <CL/opencl.hpp>

namespace hf::opencl {

struct DeviceInfo {
  int platform_index = -1;
  int device_index = -1;
  std::string platform_name;
  std::string device_name;
  std::string device_version;    // e.g. "OpenCL 3.0 PoCL ..."
  std::string opencl_c_version;  // e.g. "OpenCL C 1.2 PoCL"
  bool is_gpu = false;
  bool has_fp64 = false;              // cl_khr_fp64: reductions accumulate in double on the device
  std::size_t max_work_group_size = 1;
  unsigned long long local_mem_bytes = 0;
  unsigned compute_units = 1;

  // "P:D platform / device (GPU|CPU, OpenCL C x.y)"
  std::string describe() const;
};

// Every device of every platform, in platform order. Empty (not an error) when no platform is installed; other
// OpenCL failures are hf::Error.
std::vector<DeviceInfo> list_devices();

// The symbolic name of an OpenCL error code ("CL_INVALID_VALUE"), "CL_UNKNOWN_ERROR" for others.
const char* error_name(int code);

class Context {
 public:
  // Chooses a device as described above; device_spec overrides HF_OPENCL_DEVICE when non-empty.
  explicit Context(const std::string& device_spec = "");
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  // The process' default context (device from HF_OPENCL_DEVICE or the automatic choice), created on first use
  // and kept alive only while some caller holds the returned pointer, so nothing OpenCL outlives main().
  static std::shared_ptr<Context> shared();

  const DeviceInfo& info() const { return info_; }
  const cl::Context& context() const { return context_; }
  const cl::Device& device() const { return device_; }
  cl::CommandQueue& queue() { return queue_; }

  // The program built from `source` with `options`, compiled on first request for `key` and cached; a later
  // call with the same key returns the cached program (source and options must then be the same: they are
  // part of the cache key check and a mismatch is an hf::Error). Build failure: hf::Error
  // "OpenCL program 'KEY' failed to build on DEVICE (CL_BUILD_PROGRAM_FAILURE):\n<build log>".
  cl::Program program(const std::string& key, std::string_view source, const std::string& options = "");

  // The largest power of two <= every limit that applies to `kernel` on this device (CL_KERNEL_WORK_GROUP_SIZE,
  // CL_DEVICE_MAX_WORK_GROUP_SIZE, `cap`) and whose `local_bytes_per_item` local memory fits next to the
  // kernel's own (CL_DEVICE_LOCAL_MEM_SIZE - CL_KERNEL_LOCAL_MEM_SIZE). At least 1.
  std::size_t work_group_size(const cl::Kernel& kernel, std::size_t local_bytes_per_item, std::size_t cap) const;

  // Residency (core/device_copy.h): which host images already have a copy on this device. A stage that made an
  // image here and read it back publishes the buffer as the copy of the host bytes [host, host + bytes) and gets a
  // token (a copy of a host object in another layout, such as a map's table and pool, is published under the
  // object's address and the copy's size: KernelBuffer::resident_key); the entry holds while the token lives (the image's holder keeps it, DeviceCopies), and so does the
  // buffer. The buffer must hold those bytes when published (the producer's queue finished) and must not be written
  // afterwards: a producer allocates new buffers for its next output. A later publish for the same host bytes
  // replaces the entry. Thread-safe.
  std::shared_ptr<const void> publish(const void* host, std::size_t bytes, const cl::Buffer& buffer);
  // The published copy of (host, bytes) whose token still lives, else a null buffer (buffer() ==
  // nullptr). Counted in residency_stats().
  cl::Buffer resident(const void* host, std::size_t bytes);
  // Whether a live entry holds `buffer` (under any key): a producer that reuses its output buffers writes a new
  // one instead while this holds (a consumer may have published the same buffer again for its own copy).
  bool published(const cl::Buffer& buffer);
  struct ResidencyStats {
    std::uint64_t published = 0;  // publish() calls
    std::uint64_t hits = 0;       // resident() calls that found a copy
    std::uint64_t misses = 0;     // resident() calls that did not (the caller uploads the host bytes)
  };
  ResidencyStats residency_stats() const;
  // On by default; HF_OPENCL_RESIDENCY=0 in the environment starts a context with it off. Off, publish() publishes
  // nothing (returns null), so every stage uploads what it reads as before residency: for measuring what it saves
  // (bench_fusion_opencl BM_Pipeline/2) and for ruling it out when device results differ.
  void set_residency_enabled(bool enabled);

 private:
  struct Residency {
    std::weak_ptr<const cl::Buffer> copy;
  };
  struct Built {
    std::string source;
    std::string options;
    cl::Program program;
  };

  DeviceInfo info_;
  cl::Context context_;
  cl::Device device_;
  cl::CommandQueue queue_;
  std::mutex mutex_;
  std::map<std::string, Built> programs_;
  mutable std::mutex residency_mutex_;
  std::map<std::pair<const void*, std::size_t>, Residency> residency_;  // by (host, bytes)
  ResidencyStats residency_stats_;
  bool residency_enabled_ = true;
};

// Turns a cl::Error into hf::Error "WHAT: CALL: CL_NAME (code)"; any other exception is rethrown unchanged.
// Use as `catch (...) { rethrow_as_hf_error("opencl backend"); }`.
[[noreturn]] void rethrow_as_hf_error(const std::string& what);

// The registration kernels (registration/opencl/*.cl with the shared headers inlined), generated at build time
// by embed_opencl.cmake.
std::string_view registration_program_source();

}  // namespace hf::opencl
