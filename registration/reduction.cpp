#include "registration/reduction.h"

#include <algorithm>
#include <atomic>

#include "core/error.h"
#include "registration/cpu_backend.h"

#ifdef HF_HAVE_OPENCL_BACKEND
#include "registration/opencl/opencl_backend.h"
#endif

namespace hf {

NormalEquations NormalEquations::from_sums(const double* sums) {
  NormalEquations ne;
  int k = HF_REG_SUM_H;
  for (int i = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) {
      ne.JtJ(i, j) = sums[k];
      ne.JtJ(j, i) = sums[k];
      ++k;
    }
  }
  for (int i = 0; i < 6; ++i) ne.Jtr(i) = sums[HF_REG_SUM_G + i];
  ne.cost = sums[HF_REG_SUM_COST];
  ne.count = long(sums[HF_REG_SUM_COUNT] + 0.5);
  return ne;
}

std::vector<double> NormalEquations::to_sums() const {
  std::vector<double> sums(HF_REG_SUMS, 0.0);
  int k = HF_REG_SUM_H;
  for (int i = 0; i < 6; ++i) {
    for (int j = i; j < 6; ++j) sums[k++] = JtJ(i, j);
  }
  for (int i = 0; i < 6; ++i) sums[HF_REG_SUM_G + i] = Jtr(i);
  sums[HF_REG_SUM_COST] = cost;
  sums[HF_REG_SUM_COUNT] = double(count);
  return sums;
}

hf_transform12 to_transform12(const SE3& T) {
  hf_transform12 out{};
  const Eigen::Matrix3d R = T.rotation();
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out.m[r * 3 + c] = float(R(r, c));
  }
  for (int i = 0; i < 3; ++i) out.m[9 + i] = float(T.translation()(i));
  return out;
}

std::uint64_t new_kernel_buffer_version() {
  static std::atomic<std::uint64_t> next{1};
  return next.fetch_add(1, std::memory_order_relaxed);
}

hf_reg_maps ResidualProblem::kernel_maps() const {
  hf_reg_maps m;
  for (int i = 0; i < HF_REG_MAX_INPUTS; ++i) m.map[i] = static_cast<const float*>(maps[i].data);
  return m;
}

void validate_problem(const ResidualProblem& problem) {
  if (problem.camera.width <= 0 || problem.camera.height <= 0) {
    throw Error("registration problem: image size " + std::to_string(problem.camera.width) + "x" +
                std::to_string(problem.camera.height) + " is not positive");
  }
  const DenseKernel* k = problem.kernel;
  if (k == nullptr || k->rows == nullptr) throw Error("registration problem: no kernel");
  if (problem.params == nullptr) throw Error(std::string("registration problem: ") + k->name + ": no parameters");
  for (int slot = 0; slot < HF_REG_MAX_INPUTS; ++slot) {
    if ((k->inputs & HF_REG_IN_BIT(slot)) != 0 && problem.maps[slot].data == nullptr &&
        problem.maps[slot].buffer == nullptr) {
      throw Error(std::string("registration problem: ") + k->name + ": input map " + reg_input_name(slot) +
                  " is missing");
    }
  }
}

const char* reg_input_name(int slot) {
  static const char* const names[HF_REG_MAX_INPUTS] = {
      "cur_vertices", "cur_normals", "cur_intensity", "ref_vertices", "ref_normals", "ref_intensity",
      "ref_grad_x",   "ref_grad_y",  "method0",       "method1",      "method2",     "method3"};
  return slot >= 0 && slot < HF_REG_MAX_INPUTS ? names[slot] : "?";
}

std::vector<std::string> backend_names() { return {"cpu", "opencl"}; }

std::unique_ptr<ReductionBackend> make_backend(const std::string& name) {
  if (name == "cpu") return std::make_unique<CpuReductionBackend>();
  if (name == "opencl") {
#ifdef HF_HAVE_OPENCL_BACKEND
    return make_opencl_backend();
#else
    throw Error("OpenCL backend not built (hashfusion was configured without OpenCL); use --backend cpu");
#endif
  }
  throw Error("unknown reduction backend '" + name + "' (known: cpu, opencl)");
}

}  // namespace hf
