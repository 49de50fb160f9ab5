#include "registration/opencl/opencl_backend.h"

#include <algorithm>
#include <cstring>
#include <utility>

#include "core/error.h"

namespace hf {

std::unique_ptr<ReductionBackend> make_opencl_backend() {
  return std::make_unique<opencl::OpenClReductionBackend>();
}

namespace opencl {
namespace {

// Argument indices of hf_reg_reduce_<method> (HF_REG_OPENCL_KERNEL in registration.cl).
constexpr int kArgFirstMap = 0;  // HF_REG_MAX_INPUTS maps, by slot
constexpr int kArgIntrinsics = HF_REG_MAX_INPUTS;
constexpr int kArgTransform = kArgIntrinsics + 1;
constexpr int kArgParams = kArgTransform + 1;
constexpr int kArgGroupSums = kArgParams + 1;
constexpr int kArgScratch = kArgGroupSums + 1;

// hf_reg_reduce_rows: rows, n, group_sums, scratch.
constexpr int kRowsArgScratch = 3;
// run_groups() binds the group-sums buffer just before the scratch argument.
static_assert(kArgGroupSums == kArgScratch - 1, "group_sums must precede scratch");

static_assert(sizeof(hf_reg_row) == 8 * sizeof(float), "hf_reg_row must be J[6], r, w");
static_assert(sizeof(hf_float4) == 16, "hf_float4 must match OpenCL float4");

}  // namespace

OpenClReductionBackend::OpenClReductionBackend(std::shared_ptr<Context> context, const OpenClBackendOptions& options)
    : context_(std::move(context)), options_(options) {
  if (!context_) throw Error("OpenCL backend: no context");
  options_.pixels_per_item = std::max(1, options_.pixels_per_item);
  use_double_ = options_.allow_double && context_->info().has_fp64;
  try {
    // Correctly rounded division and square root, as in C++, for the same accept/reject decisions per pixel.
    std::string build_options = "-cl-fp32-correctly-rounded-divide-sqrt";
    if (use_double_) build_options += " -DHF_REG_REDUCE_DOUBLE=1";
    build_options_ = build_options;
    program_ = context_->program(use_double_ ? "registration-double" : "registration-float",
                                 registration_program_source(), build_options_);
    rows_kernel_ = cl::Kernel(program_, "hf_reg_reduce_rows");
    queue_ = cl::CommandQueue(context_->context(), context_->device());
    // One work-group size for every kernel of the program (the built-in methods' and the rows kernel).
    std::vector<cl::Kernel> kernels;
    program_.createKernels(&kernels);
    work_group_size_ = options_.max_work_group_size;
    for (const cl::Kernel& k : kernels) {
      work_group_size_ = std::min(work_group_size_, context_->work_group_size(k, bytes_per_item(), work_group_size_));
    }
    dummy_ = cl::Buffer(context_->context(), CL_MEM_READ_ONLY, sizeof(hf_float4));
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_as_hf_error("OpenCL backend on " + context_->info().describe());
  }
}

std::size_t OpenClReductionBackend::bytes_per_item() const {
  return HF_REG_SUMS * (use_double_ ? sizeof(double) : sizeof(float));
}

cl::Kernel& OpenClReductionBackend::method_kernel(const DenseKernel& method) {
  auto it = kernels_.find(method.name);
  if (it != kernels_.end()) return it->second;
  const std::string entry = std::string("hf_reg_reduce_") + method.name;
  cl::Kernel kernel;
  if (method.opencl_source != nullptr && method.opencl_source[0] != '\0') {
    // A method registered at run time: the shared part of the program plus its own kernel header.
    const std::string source = std::string(registration_program_source()) + "\n" + method.opencl_source;
    cl::Program program = context_->program(std::string(use_double_ ? "registration-double-" : "registration-float-") +
                                                method.name,
                                            source, build_options_);
    kernel = cl::Kernel(program, entry.c_str());
  } else {
    try {
      kernel = cl::Kernel(program_, entry.c_str());
    } catch (const cl::Error&) {
      throw Error("OpenCL backend: method '" + std::string(method.name) + "' has no OpenCL kernel " + entry +
                  " (its kernel header is not in registration/methods.def and it brings no opencl_source)");
    }
  }
  if (context_->work_group_size(kernel, bytes_per_item(), work_group_size_) < work_group_size_) {
    throw Error("OpenCL backend: kernel " + entry + " does not fit the work-group size " +
                std::to_string(work_group_size_));
  }
  return kernels_.emplace(method.name, kernel).first->second;
}

cl::Buffer& OpenClReductionBackend::slot_buffer(int slot, const void* data, std::size_t bytes) {
  Slot& s = slots_[slot];
  if (s.capacity < bytes) {
    s.buffer = cl::Buffer(context_->context(), CL_MEM_READ_ONLY, bytes);
    s.capacity = bytes;
  }
  // Non-blocking: the in-order queue runs the kernel after the copy, and the caller's maps must stay alive and
  // unchanged until reduce() returns (it waits for the result), which the ResidualProblem contract guarantees.
  queue_.enqueueWriteBuffer(s.buffer, CL_FALSE, 0, bytes, data);
  s.source = data;
  s.bytes = bytes;
  s.bound = s.buffer;
  return s.buffer;
}

void OpenClReductionBackend::upload_inputs(const ResidualProblem& p, cl::Kernel& kernel) {
  const std::size_t n = std::size_t(p.width()) * std::size_t(p.height());
  // Per-pixel maps: all again when the inputs version, the size or a pointer changed.
  bool same = have_inputs_ && inputs_version_ == p.inputs_version && width_ == p.width() && height_ == p.height();
  for (int i = 0; i < HF_REG_MAX_INPUTS && same; ++i)
    same = p.maps[i].buffer != nullptr || slots_[i].source == p.maps[i].data;
  if (!same) {
    for (int i = 0; i < HF_REG_MAX_INPUTS; ++i) {
      if (p.maps[i].buffer != nullptr) continue;
      slots_[i].buffer_source = nullptr;
      if (p.maps[i].data == nullptr) {
        slots_[i].source = nullptr;
        slots_[i].bytes = 0;
      } else if (cl::Buffer copy = context_->resident(p.maps[i].data, n * p.maps[i].bytes_per_pixel); copy()) {
        // Made on this device and still true (its holder keeps the token): bind it, nothing crosses.
        slots_[i].source = p.maps[i].data;
        slots_[i].bytes = n * p.maps[i].bytes_per_pixel;
        slots_[i].bound = copy;
        ++resident_binds_;
      } else {
        slot_buffer(i, p.maps[i].data, n * p.maps[i].bytes_per_pixel);
        ++map_uploads_;
      }
    }
    have_inputs_ = true;
    inputs_version_ = p.inputs_version;
    width_ = p.width();
    height_ = p.height();
    ++uploads_;
  }
  // Kernel buffers: each on its own version, which outlives levels and calls.
  for (int i = 0; i < HF_REG_MAX_INPUTS; ++i) {
    const KernelBuffer* b = p.maps[i].buffer;
    if (b == nullptr) continue;
    Slot& s = slots_[i];
    const std::uint64_t version = b->version();
    if (s.buffer_source != b || s.buffer_version != version || s.source == nullptr) {
      s.buffer_source = b;
      s.buffer_version = version;
      // Kept on this device by the stage that owns it (sdf: the device map's table and pool): bind it in place.
      if (const auto [key, key_bytes] = b->resident_key(); key != nullptr) {
        if (cl::Buffer copy = context_->resident(key, key_bytes); copy() != nullptr) {
          s.source = key;
          s.bytes = key_bytes;
          s.bound = copy;
          ++resident_binds_;
          continue;
        }
      }
      const auto [data, bytes] = b->contents();
      if (data == nullptr || bytes == 0) throw Error("OpenCL backend: kernel buffer in slot " +
                                                     std::string(reg_input_name(i)) + " is empty");
      slot_buffer(i, data, bytes);
      ++buffer_uploads_;
    }
  }
  // Arguments belong to the kernel object (one per method): bind the slots every time, which is cheap.
  for (int i = 0; i < HF_REG_MAX_INPUTS; ++i) {
    kernel.setArg(kArgFirstMap + i, slots_[i].source == nullptr ? dummy_ : slots_[i].bound);
  }
}

std::vector<double> OpenClReductionBackend::run_groups(cl::Kernel& kernel, std::size_t items, int first_local_arg) {
  const std::size_t ls = work_group_size_;
  const std::size_t per_group = ls * std::size_t(options_.pixels_per_item);
  const std::size_t groups = std::max<std::size_t>(1, (items + per_group - 1) / per_group);
  const std::size_t acc = use_double_ ? sizeof(double) : sizeof(float);
  const std::size_t bytes = groups * HF_REG_SUMS * acc;
  if (group_sums_capacity_ < bytes) {
    group_sums_ = cl::Buffer(context_->context(), CL_MEM_WRITE_ONLY, bytes);
    group_sums_capacity_ = bytes;
  }
  kernel.setArg(first_local_arg - 1, group_sums_);
  kernel.setArg(first_local_arg, cl::Local(HF_REG_SUMS * ls * acc));
  queue_.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(groups * ls), cl::NDRange(ls));
  host_group_sums_.resize(bytes);
  queue_.enqueueReadBuffer(group_sums_, CL_TRUE, 0, bytes, host_group_sums_.data());
  // Stage two: the group rows in group order, in double (deterministic for a given device and group size).
  std::vector<double> total(HF_REG_SUMS, 0.0);
  for (std::size_t g = 0; g < groups; ++g) {
    for (int k = 0; k < HF_REG_SUMS; ++k) {
      const std::size_t at = (g * HF_REG_SUMS + std::size_t(k)) * acc;
      if (use_double_) {
        double v;
        std::memcpy(&v, host_group_sums_.data() + at, sizeof v);
        total[k] += v;
      } else {
        float v;
        std::memcpy(&v, host_group_sums_.data() + at, sizeof v);
        total[k] += double(v);
      }
    }
  }
  return total;
}

NormalEquations OpenClReductionBackend::reduce(const ResidualProblem& problem) {
  validate_problem(problem);
  try {
    cl::Kernel& kernel = method_kernel(*problem.kernel);
    upload_inputs(problem, kernel);
    kernel.setArg(kArgIntrinsics, sizeof(hf_intrinsics), &problem.camera);
    kernel.setArg(kArgTransform, sizeof(hf_transform12), &problem.T_ref_cur);
    kernel.setArg(kArgParams, problem.kernel->params_bytes, problem.params);
    const std::size_t pixels = std::size_t(problem.width()) * std::size_t(problem.height());
    const std::vector<double> sums = run_groups(kernel, pixels, kArgScratch);
    return NormalEquations::from_sums(sums.data());
  } catch (const Error&) {
    throw;
  } catch (...) {
    // A failed enqueue may have left the buffers half-written: upload again next time.
    have_inputs_ = false;
    for (Slot& slot : slots_) slot.buffer_source = nullptr;
    rethrow_as_hf_error("OpenCL backend");
  }
}

std::vector<double> OpenClReductionBackend::reduce_rows(const std::vector<hf_reg_row>& rows) {
  try {
    const std::size_t bytes = std::max<std::size_t>(rows.size(), 1) * sizeof(hf_reg_row);
    cl::Buffer buffer(context_->context(), CL_MEM_READ_ONLY, bytes);
    if (!rows.empty()) queue_.enqueueWriteBuffer(buffer, CL_FALSE, 0, rows.size() * sizeof(hf_reg_row), rows.data());
    rows_kernel_.setArg(0, buffer);
    rows_kernel_.setArg(1, cl_int(rows.size()));
    return run_groups(rows_kernel_, rows.size(), kRowsArgScratch);
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_as_hf_error("OpenCL backend (reduce_rows)");
  }
}

}  // namespace opencl
}  // namespace hf
