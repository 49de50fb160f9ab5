// The OpenCL reduction backend ("opencl"): the per-pixel rows of the problem's method evaluated by its OpenCL
// kernel hf_reg_reduce_<name> (registration/opencl/registration.cl plus the method's kernel header, the same header
// the C++ backend compiles) and reduced in two stages: a work-group tree in local memory, then a host sum of the
// group rows in double. A method registered at run time brings its kernel's source (DenseKernel::opencl_source),
// built into a program of its own on first use.
//
//   auto backend = hf::make_opencl_backend();            // throws hf::Error when there is no OpenCL platform
//   hf::NormalEquations ne = backend->reduce(problem);   // same contract as every ReductionBackend
//
// Device: hf::opencl::Context::shared() (HF_OPENCL_DEVICE, else a GPU, else any device; opencl_context.h). The
// program is built once per context (PoCL also caches binaries in POCL_CACHE_DIR across runs).
// Precision: on devices with cl_khr_fp64 the device accumulates in double and forms each row's products exactly as
// the C++ backend does, so the two agree to the order of the double additions (tests: 1e-6 relative on the
// normal equations, far tighter in practice); without fp64 the device sums in float (pairwise in the group tree).
// Buffers: one per input slot (HF_REG_MAX_INPUTS), allocated once at the largest size seen and reused; the input
// maps are uploaded only when ResidualProblem::inputs_version, a map pointer or the size changes (the driver keeps
// them across the iterations of one level), so an iteration uploads only its pose and parameters. A map that already
// has a copy on the device (core/device_copy.h: the device pyramid's and the device raycast's outputs, published
// on the context) is bound, not uploaded: with --backend opencl only the pose, the parameters and the 29 sums cross.
// A slot holding a KernelBuffer (a method's table, reduction.h) is uploaded when that buffer or its version changes.
// Failures: hf::Error for a malformed problem (validate_problem), for a method without an OpenCL kernel and for any
// OpenCL error (naming the call and the error code). Thread-safety: one thread at a time per backend object (own
// command queue); several backends may share the context from different threads.
#pragma once

#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "core/opencl/opencl_context.h"
#include "registration/reduction.h"

namespace hf {

// The "opencl" entry of make_backend(): an OpenClReductionBackend on the shared default context.
std::unique_ptr<ReductionBackend> make_opencl_backend();

namespace opencl {

struct OpenClBackendOptions {
  std::size_t max_work_group_size = 256;  // upper bound; the device and the kernel may lower it
  int pixels_per_item = 4;                // pixels each work-item evaluates (grid-stride); >= 1
  bool allow_double = true;               // accumulate in double when the device has cl_khr_fp64
};

class OpenClReductionBackend final : public ReductionBackend {
 public:
  explicit OpenClReductionBackend(std::shared_ptr<Context> context = Context::shared(),
                                  const OpenClBackendOptions& options = {});
  NormalEquations reduce(const ResidualProblem& problem) override;
  std::string name() const override { return "opencl"; }

  // The same two-stage reduction over given rows (no per-pixel evaluation): the 29 sums in the order of
  // reg_common.h. For tests of the reduction itself.
  std::vector<double> reduce_rows(const std::vector<hf_reg_row>& rows);

  const Context& context() const { return *context_; }
  std::size_t work_group_size() const { return work_group_size_; }
  bool accumulates_in_double() const { return use_double_; }
  // How many times the input maps were uploaded (one per new inputs_version / pointer set), for tests.
  std::uint64_t uploads() const { return uploads_; }
  // How many times a KernelBuffer was uploaded (one per new buffer or version), for tests.
  std::uint64_t buffer_uploads() const { return buffer_uploads_; }
  // Of the maps of those input sets: how many were uploaded from the host, how many bound to a device copy.
  std::uint64_t map_uploads() const { return map_uploads_; }
  std::uint64_t resident_binds() const { return resident_binds_; }

 private:
  // One input map slot: the device buffer (capacity in bytes) and what it currently holds.
  struct Slot {
    cl::Buffer buffer;  // the slot's own buffer, for uploads
    std::size_t capacity = 0;
    cl::Buffer bound;   // what the kernel reads: `buffer`, or a device copy of the host map (Context::resident)
    const void* source = nullptr;
    std::size_t bytes = 0;
    // A KernelBuffer's slot: the buffer and the version the device copy holds (source: its contents' pointer).
    const KernelBuffer* buffer_source = nullptr;
    std::uint64_t buffer_version = 0;
  };

  void upload_inputs(const ResidualProblem& problem, cl::Kernel& kernel);
  cl::Kernel& method_kernel(const DenseKernel& method);
  std::size_t bytes_per_item() const;
  cl::Buffer& slot_buffer(int slot, const void* data, std::size_t bytes);
  std::vector<double> run_groups(cl::Kernel& kernel, std::size_t items, int first_local_arg);

  std::shared_ptr<Context> context_;
  OpenClBackendOptions options_;
  cl::CommandQueue queue_;
  std::string build_options_;
  cl::Program program_;
  std::map<std::string, cl::Kernel> kernels_;  // by method name
  cl::Kernel rows_kernel_;
  bool use_double_ = false;
  std::size_t work_group_size_ = 1;
  Slot slots_[HF_REG_MAX_INPUTS];
  cl::Buffer dummy_;
  cl::Buffer group_sums_;
  std::size_t group_sums_capacity_ = 0;
  std::vector<unsigned char> host_group_sums_;
  bool have_inputs_ = false;
  std::uint64_t inputs_version_ = 0;
  int width_ = 0, height_ = 0;
  std::uint64_t uploads_ = 0;
  std::uint64_t buffer_uploads_ = 0;
  std::uint64_t map_uploads_ = 0;
  std::uint64_t resident_binds_ = 0;
};

}  // namespace opencl
}  // namespace hf
