#include "core/opencl/opencl_context.h"

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <sstream>
#include <utility>

#include "core/error.h"

namespace hf::opencl {
namespace {

constexpr const char* kNoPlatform = "no OpenCL platform found: install pocl-opencl-icd or use --backend cpu";

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\0' || std::isspace(static_cast<unsigned char>(s.back())))) s.pop_back();
  size_t i = 0;
  while (i < s.size() && std::isspace(static_cast<unsigned char>(s[i]))) ++i;
  return s.substr(i);
}

std::vector<cl::Platform> platforms_or_empty() {
  std::vector<cl::Platform> platforms;
  try {
    cl::Platform::get(&platforms);
  } catch (const cl::Error& e) {
    // The ICD loader reports "no platform" as an error code rather than an empty list.
    if (e.err() == CL_PLATFORM_NOT_FOUND_KHR) return {};
    throw;
  }
  return platforms;
}

DeviceInfo describe_device(const cl::Platform& platform, const cl::Device& device, int p, int d) {
  DeviceInfo info;
  info.platform_index = p;
  info.device_index = d;
  info.platform_name = trim(platform.getInfo<CL_PLATFORM_NAME>());
  info.device_name = trim(device.getInfo<CL_DEVICE_NAME>());
  info.device_version = trim(device.getInfo<CL_DEVICE_VERSION>());
  info.opencl_c_version = trim(device.getInfo<CL_DEVICE_OPENCL_C_VERSION>());
  info.is_gpu = (device.getInfo<CL_DEVICE_TYPE>() & CL_DEVICE_TYPE_GPU) != 0;
  const std::string extensions = device.getInfo<CL_DEVICE_EXTENSIONS>();
  info.has_fp64 = extensions.find("cl_khr_fp64") != std::string::npos;
  info.max_work_group_size = device.getInfo<CL_DEVICE_MAX_WORK_GROUP_SIZE>();
  info.local_mem_bytes = device.getInfo<CL_DEVICE_LOCAL_MEM_SIZE>();
  info.compute_units = device.getInfo<CL_DEVICE_MAX_COMPUTE_UNITS>();
  return info;
}

struct Candidate {
  DeviceInfo info;
  cl::Device device;
  cl_device_type type = 0;
};

std::vector<Candidate> enumerate() {
  std::vector<Candidate> all;
  const std::vector<cl::Platform> platforms = platforms_or_empty();
  for (size_t p = 0; p < platforms.size(); ++p) {
    std::vector<cl::Device> devices;
    try {
      platforms[p].getDevices(CL_DEVICE_TYPE_ALL, &devices);
    } catch (const cl::Error& e) {
      if (e.err() == CL_DEVICE_NOT_FOUND) continue;  // a platform with no usable device
      throw;
    }
    for (size_t d = 0; d < devices.size(); ++d) {
      all.push_back({describe_device(platforms[p], devices[d], int(p), int(d)), devices[d],
                     devices[d].getInfo<CL_DEVICE_TYPE>()});
    }
  }
  return all;
}

std::string device_list(const std::vector<Candidate>& all) {
  std::string out;
  for (const Candidate& c : all) out += "\n  " + c.info.describe();
  return out;
}

const Candidate& choose(const std::vector<Candidate>& all, const std::string& spec) {
  if (spec.empty()) {
    for (const Candidate& c : all) {
      if (c.type & CL_DEVICE_TYPE_GPU) return c;
    }
    return all.front();
  }
  const std::string s = lower(trim(spec));
  const size_t colon = s.find(':');
  if (colon != std::string::npos && colon > 0 && colon + 1 < s.size() &&
      std::all_of(s.begin(), s.end(), [](char ch) { return ch == ':' || std::isdigit(static_cast<unsigned char>(ch)); })) {
    const int p = std::atoi(s.substr(0, colon).c_str());
    const int d = std::atoi(s.substr(colon + 1).c_str());
    for (const Candidate& c : all) {
      if (c.info.platform_index == p && c.info.device_index == d) return c;
    }
  } else {
    cl_device_type want = 0;
    if (s == "gpu") want = CL_DEVICE_TYPE_GPU;
    if (s == "cpu") want = CL_DEVICE_TYPE_CPU;
    if (s == "accelerator") want = CL_DEVICE_TYPE_ACCELERATOR;
    for (const Candidate& c : all) {
      if (want != 0 ? (c.type & want) != 0
                    : lower(c.info.platform_name + " / " + c.info.device_name).find(s) != std::string::npos) {
        return c;
      }
    }
  }
  throw Error("OpenCL device '" + spec + "' (HF_OPENCL_DEVICE or --opencl-device) matches no device; expected P:D, "
              "gpu, cpu, accelerator or part of a name; devices:" + device_list(all));
}

std::string build_log(const cl::Program& program, const cl::Device& device) {
  try {
    return trim(program.getBuildInfo<CL_PROGRAM_BUILD_LOG>(device));
  } catch (const cl::Error&) {
    return "(no build log available)";
  }
}

}  // namespace

std::string DeviceInfo::describe() const {
  std::ostringstream out;
  out << platform_index << ':' << device_index << ' ' << platform_name << " / " << device_name << " ("
      << (is_gpu ? "GPU" : "CPU or other") << ", " << opencl_c_version << ")";
  return out.str();
}

const char* error_name(int code) {
  switch (code) {
#define HF_CL_CASE(name) \
  case name:             \
    return #name;
    HF_CL_CASE(CL_SUCCESS)
    HF_CL_CASE(CL_DEVICE_NOT_FOUND)
    HF_CL_CASE(CL_DEVICE_NOT_AVAILABLE)
    HF_CL_CASE(CL_COMPILER_NOT_AVAILABLE)
    HF_CL_CASE(CL_MEM_OBJECT_ALLOCATION_FAILURE)
    HF_CL_CASE(CL_OUT_OF_RESOURCES)
    HF_CL_CASE(CL_OUT_OF_HOST_MEMORY)
    HF_CL_CASE(CL_PROFILING_INFO_NOT_AVAILABLE)
    HF_CL_CASE(CL_MEM_COPY_OVERLAP)
    HF_CL_CASE(CL_IMAGE_FORMAT_MISMATCH)
    HF_CL_CASE(CL_IMAGE_FORMAT_NOT_SUPPORTED)
    HF_CL_CASE(CL_BUILD_PROGRAM_FAILURE)
    HF_CL_CASE(CL_MAP_FAILURE)
    HF_CL_CASE(CL_MISALIGNED_SUB_BUFFER_OFFSET)
    HF_CL_CASE(CL_COMPILE_PROGRAM_FAILURE)
    HF_CL_CASE(CL_LINKER_NOT_AVAILABLE)
    HF_CL_CASE(CL_LINK_PROGRAM_FAILURE)
    HF_CL_CASE(CL_INVALID_VALUE)
    HF_CL_CASE(CL_INVALID_DEVICE_TYPE)
    HF_CL_CASE(CL_INVALID_PLATFORM)
    HF_CL_CASE(CL_INVALID_DEVICE)
    HF_CL_CASE(CL_INVALID_CONTEXT)
    HF_CL_CASE(CL_INVALID_QUEUE_PROPERTIES)
    HF_CL_CASE(CL_INVALID_COMMAND_QUEUE)
    HF_CL_CASE(CL_INVALID_HOST_PTR)
    HF_CL_CASE(CL_INVALID_MEM_OBJECT)
    HF_CL_CASE(CL_INVALID_BINARY)
    HF_CL_CASE(CL_INVALID_BUILD_OPTIONS)
    HF_CL_CASE(CL_INVALID_PROGRAM)
    HF_CL_CASE(CL_INVALID_PROGRAM_EXECUTABLE)
    HF_CL_CASE(CL_INVALID_KERNEL_NAME)
    HF_CL_CASE(CL_INVALID_KERNEL_DEFINITION)
    HF_CL_CASE(CL_INVALID_KERNEL)
    HF_CL_CASE(CL_INVALID_ARG_INDEX)
    HF_CL_CASE(CL_INVALID_ARG_VALUE)
    HF_CL_CASE(CL_INVALID_ARG_SIZE)
    HF_CL_CASE(CL_INVALID_KERNEL_ARGS)
    HF_CL_CASE(CL_INVALID_WORK_DIMENSION)
    HF_CL_CASE(CL_INVALID_WORK_GROUP_SIZE)
    HF_CL_CASE(CL_INVALID_WORK_ITEM_SIZE)
    HF_CL_CASE(CL_INVALID_GLOBAL_OFFSET)
    HF_CL_CASE(CL_INVALID_EVENT_WAIT_LIST)
    HF_CL_CASE(CL_INVALID_EVENT)
    HF_CL_CASE(CL_INVALID_OPERATION)
    HF_CL_CASE(CL_INVALID_BUFFER_SIZE)
    HF_CL_CASE(CL_INVALID_GLOBAL_WORK_SIZE)
    HF_CL_CASE(CL_PLATFORM_NOT_FOUND_KHR)
#undef HF_CL_CASE
    default:
      return "CL_UNKNOWN_ERROR";
  }
}

void rethrow_as_hf_error(const std::string& what) {
  try {
    throw;
  } catch (const cl::Error& e) {
    throw Error(what + ": " + e.what() + ": " + error_name(e.err()) + " (" + std::to_string(e.err()) + ")");
  }
}

std::vector<DeviceInfo> list_devices() {
  try {
    std::vector<DeviceInfo> out;
    for (const Candidate& c : enumerate()) out.push_back(c.info);
    return out;
  } catch (...) {
    rethrow_as_hf_error("listing OpenCL devices");
  }
}

Context::Context(const std::string& device_spec) {
  try {
    const std::vector<Candidate> all = enumerate();
    if (all.empty()) throw Error(kNoPlatform);
    std::string spec = device_spec;
    if (spec.empty()) {
      const char* env = std::getenv("HF_OPENCL_DEVICE");
      if (env != nullptr) spec = env;
    }
    const Candidate& chosen = choose(all, spec);
    info_ = chosen.info;
    device_ = chosen.device;
    context_ = cl::Context(device_);
    queue_ = cl::CommandQueue(context_, device_);
    const char* residency = std::getenv("HF_OPENCL_RESIDENCY");
    residency_enabled_ = residency == nullptr || std::string(residency) != "0";
  } catch (...) {
    rethrow_as_hf_error("creating the OpenCL context");
  }
}

std::shared_ptr<Context> Context::shared() {
  static std::mutex mutex;
  static std::weak_ptr<Context> current;
  std::lock_guard<std::mutex> lock(mutex);
  std::shared_ptr<Context> ctx = current.lock();
  if (!ctx) {
    ctx = std::make_shared<Context>();
    current = ctx;
  }
  return ctx;
}

std::shared_ptr<const void> Context::publish(const void* host, std::size_t bytes, const cl::Buffer& buffer) {
  if (host == nullptr || bytes == 0 || buffer() == nullptr) return nullptr;
  std::lock_guard<std::mutex> lock(residency_mutex_);
  if (!residency_enabled_) return nullptr;
  auto copy = std::make_shared<const cl::Buffer>(buffer);
  // Entries whose holders dropped them go first: the table stays as small as the live copies.
  std::erase_if(residency_, [](const auto& entry) { return entry.second.copy.expired(); });
  residency_[{host, bytes}] = Residency{copy};
  ++residency_stats_.published;
  return copy;
}

cl::Buffer Context::resident(const void* host, std::size_t bytes) {
  std::lock_guard<std::mutex> lock(residency_mutex_);
  auto it = residency_.find({host, bytes});
  if (it != residency_.end()) {
    if (const std::shared_ptr<const cl::Buffer> copy = it->second.copy.lock()) {
      ++residency_stats_.hits;
      return *copy;
    }
  }
  ++residency_stats_.misses;
  return cl::Buffer();
}

bool Context::published(const cl::Buffer& buffer) {
  std::lock_guard<std::mutex> lock(residency_mutex_);
  for (const auto& [key, entry] : residency_) {
    const std::shared_ptr<const cl::Buffer> copy = entry.copy.lock();
    if (copy && (*copy)() == buffer()) return true;
  }
  return false;
}

void Context::set_residency_enabled(bool enabled) {
  std::lock_guard<std::mutex> lock(residency_mutex_);
  residency_enabled_ = enabled;
  if (!enabled) residency_.clear();
}

Context::ResidencyStats Context::residency_stats() const {
  std::lock_guard<std::mutex> lock(residency_mutex_);
  return residency_stats_;
}

cl::Program Context::program(const std::string& key, std::string_view source, const std::string& options) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = programs_.find(key);
  if (it != programs_.end()) {
    if (it->second.source != source || it->second.options != options) {
      throw Error("OpenCL program '" + key + "' was requested again with a different source or options");
    }
    return it->second.program;
  }
  cl::Program program;
  try {
    program = cl::Program(context_, std::string(source));
  } catch (...) {
    rethrow_as_hf_error("creating OpenCL program '" + key + "'");
  }
  try {
    program.build(std::vector<cl::Device>{device_}, options.c_str());
  } catch (const cl::Error& e) {
    throw Error("OpenCL program '" + key + "' failed to build on " + info_.describe() + " (" + error_name(e.err()) +
                ", options '" + options + "'):\n" + build_log(program, device_));
  }
  programs_.emplace(key, Built{std::string(source), options, program});
  return program;
}

std::size_t Context::work_group_size(const cl::Kernel& kernel, std::size_t local_bytes_per_item,
                                     std::size_t cap) const {
  try {
    std::size_t limit = std::min(info_.max_work_group_size, kernel.getWorkGroupInfo<CL_KERNEL_WORK_GROUP_SIZE>(device_));
    limit = std::min(limit, std::max<std::size_t>(cap, 1));
    if (local_bytes_per_item > 0) {
      const unsigned long long used = kernel.getWorkGroupInfo<CL_KERNEL_LOCAL_MEM_SIZE>(device_);
      const unsigned long long free = info_.local_mem_bytes > used ? info_.local_mem_bytes - used : 0;
      limit = std::min<std::size_t>(limit, std::size_t(free / local_bytes_per_item));
    }
    std::size_t size = 1;
    while (size * 2 <= limit) size *= 2;
    return size;
  } catch (...) {
    rethrow_as_hf_error("querying the OpenCL work-group size");
  }
}

}  // namespace hf::opencl
