// Reduction backends: evaluate one level's per-pixel rows of a method's kernel (ResidualProblem::kernel, built from
// its registration/kernels/<method>_kernel.h) and reduce them to the 29 values of the normal equations (order in
// registration/kernels/reg_common.h). A backend consults only the kernel's descriptor, never a method name.
//
//   auto backend = hf::make_backend("cpu");             // or "opencl"
//   hf::NormalEquations ne = backend->reduce(problem);  // H = ne.JtJ, g = ne.Jtr; solve H xi = -g
//
// The Gauss-Newton driver (registration/gauss_newton.h) owns everything else; a backend only sums.
// Thread-safety: a backend object is used by one thread at a time (reduce() may use many threads inside).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/se3.h"
#include "registration/kernels/reg_common.h"

namespace hf {

// The normal equations of one Gauss-Newton iteration: JtJ = sum w J^T J (symmetric), Jtr = sum w J^T r,
// cost = sum w r^2, count = number of rows (residuals with a correspondence).
struct NormalEquations {
  Matrix6d JtJ = Matrix6d::Zero();
  Vector6d Jtr = Vector6d::Zero();
  double cost = 0.0;
  long count = 0;

  // From the 29 sums in the documented order; the lower triangle of JtJ is mirrored from the upper.
  static NormalEquations from_sums(const double* sums);
  // The 29 sums back (for tests and for backends that combine partial results).
  std::vector<double> to_sums() const;
};

struct ResidualProblem;

// Sums the rows of current-frame pixel rows [y_begin, y_end) of `problem` into sums (HF_REG_SUMS doubles, the
// order of registration/kernels/reg_common.h). Called concurrently for disjoint row ranges.
using RowsFunction = void (*)(const ResidualProblem& problem, int y_begin, int y_end, double* sums);

// A per-pixel least-squares method as the backends see it (registration/dense_method.h builds one from a kernel
// header). Static data: one per method, alive for the whole program.
struct DenseKernel {
  const char* name = "";   // the registry name; the OpenCL kernel is hf_reg_reduce_<name>
  unsigned inputs = 0;     // HF_REG_IN_BIT() of every map slot the pixel function reads
  int max_rows = 1;        // rows per pixel, at most (<= HF_REG_MAX_ROWS)
  // sizeof the kernel's parameter struct (passed by value to OpenCL). The C++ rows may read a host struct that
  // begins with it and adds host-only fields (sdf: the grid); a backend copies only these bytes.
  std::size_t params_bytes = 0;
  // The scalar per-pixel function of the kernel header, for one pixel (tests, references).
  int (*pixel)(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const void* params,
               hf_reg_row* rows) = nullptr;
  RowsFunction rows = nullptr;       // the pixel function over rows, summed in double (the "cpu" backend)
  RowsFunction rows_avx2 = nullptr;  // the same rows eight pixels at a time; null: the cpu backend runs `rows`
  // OpenCL C source of the kernel (its header's text) for a method whose kernel is not in the embedded program
  // (one registered at run time); empty for the built-in methods.
  const char* opencl_source = "";
};

// A method slot's input that is not a per-pixel map but a buffer of its own size and lifetime (sdf: the map's
// block hash and voxel pool in the flat layout of fusion/kernels/block_hash.h), which only a backend running the
// kernel's pixel function away from host memory reads: the cpu backend's rows read the method's host structure
// (sdf: the VoxelBlockGrid) and never ask for it, so it is built on demand, and a device backend keeps its
// uploaded copy while version() holds, across levels and registration calls (unlike ResidualProblem::
// inputs_version, which changes per level).
class KernelBuffer {
 public:
  virtual ~KernelBuffer() = default;
  // Changes whenever the contents change, to a value no buffer had before (new_kernel_buffer_version()): a backend
  // may meet a new buffer at the address of a destroyed one, and must not take it for the old contents.
  virtual std::uint64_t version() const = 0;
  // The contents in the kernel's layout, built when first asked after a change; valid until the next change.
  // Never empty (a kernel reading an empty map gets a buffer it does not index).
  virtual std::pair<const void*, std::size_t> contents() const = 0;
  // Where a device may hold these contents already: the key (the host object they mirror, the copy's size in
  // bytes) under which the stage that keeps them there published its copy (core/device_copy.h; sdf: the device
  // map's table and pool, DeviceVoxelGrid::publish_map). A device backend binds that copy, when there is one,
  // instead of building and uploading contents(). {nullptr, 0}: none.
  virtual std::pair<const void*, std::size_t> resident_key() const { return {nullptr, 0}; }
};

// A version for a KernelBuffer's new contents, unique in the process (thread-safe).
std::uint64_t new_kernel_buffer_version();

// One level's inputs for one method: its kernel, the maps it reads, its parameters. The maps and params are owned
// by the caller (they must outlive reduce()). Frames: see registration/kernels/reg_common.h (v = T_ref_cur v_cur).
struct ResidualProblem {
  struct Map {
    const void* data = nullptr;
    std::size_t bytes_per_pixel = 0;  // sizeof(hf_float4) or sizeof(float) for the pyramid's maps
    // Instead of data: a buffer (KernelBuffer above). The kernel's C++ rows see a null map in this slot.
    const KernelBuffer* buffer = nullptr;
  };
  const DenseKernel* kernel = nullptr;
  hf_intrinsics camera{};  // intrinsics and size of this level (shared by the current and the reference maps)
  Map maps[HF_REG_MAX_INPUTS];  // by HF_REG_IN_* slot: camera.width x camera.height, row-major
  hf_transform12 T_ref_cur{};  // the current estimate (rotation row-major, then translation)
  const void* params = nullptr;  // the kernel's parameter struct (kernel->params_bytes)
  // Only current pixels with x and y multiples of this can give rows (a hint: backends may skip the others).
  int pixel_step = 1;
  // Changes whenever any map pointer or its contents change (the driver bumps it per registration call and
  // level); constant across the iterations of one level, so a backend may keep uploaded copies while it matches.
  std::uint64_t inputs_version = 0;

  int width() const { return camera.width; }
  int height() const { return camera.height; }
  // The maps as the kernels read them.
  hf_reg_maps kernel_maps() const;
  void set_map(int slot, const hf_float4* data) { maps[slot] = {data, sizeof(hf_float4)}; }
  void set_map(int slot, const float* data) { maps[slot] = {data, sizeof(float)}; }
  void set_buffer(int slot, const KernelBuffer* buffer) { maps[slot] = {nullptr, 0, buffer}; }
};

// hf_transform12 of an SE3 (float).
hf_transform12 to_transform12(const SE3& T);

class ReductionBackend {
 public:
  virtual ~ReductionBackend() = default;
  // The reduced normal equations of `problem`. Throws hf::Error only for a malformed problem (null map that the
  // method reads, non-positive size) or a device failure; the driver turns exceptions into a failed result.
  virtual NormalEquations reduce(const ResidualProblem& problem) = 0;
  virtual std::string name() const = 0;  // "cpu", "opencl"
};

// The backend registry: "cpu" (default, always available) or "opencl". Throws hf::Error naming the known backends
// for an unknown name, and hf::Error "OpenCL backend not built" when the OpenCL target is not linked (or the
// OpenCL factory's own error when no platform/device is present).
std::unique_ptr<ReductionBackend> make_backend(const std::string& name = "cpu");
std::vector<std::string> backend_names();

// Checks the kernel, the pointers it reads, the params and the size; throws hf::Error naming the problem.
void validate_problem(const ResidualProblem& problem);
// "cur_vertices", ... for an HF_REG_IN_* slot (messages).
const char* reg_input_name(int slot);

}  // namespace hf
