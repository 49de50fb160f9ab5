#include "core/opencl/push_pull_opencl.h"

#include <mutex>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/opencl/opencl_context.h"

namespace hf::opencl {

// The push-pull program (core/opencl/push_pull.cl with its headers inlined), generated at build time.
std::string_view push_pull_program_source();

struct PushPullOpenCl::State {
  std::shared_ptr<Context> context;
  cl::CommandQueue queue;
  cl::Kernel push, pull;
};

PushPullOpenCl::PushPullOpenCl(std::shared_ptr<Context> context) : state_(std::make_unique<State>()) {
  state_->context = context ? std::move(context) : Context::shared();
  try {
    // Correctly rounded division, as in C++, so the averages agree to the last bit on conforming devices.
    cl::Program program =
        state_->context->program("push_pull", push_pull_program_source(), "-cl-fp32-correctly-rounded-divide-sqrt");
    state_->push = cl::Kernel(program, "hf_push_pull_push");
    state_->pull = cl::Kernel(program, "hf_push_pull_pull");
    state_->queue = cl::CommandQueue(state_->context->context(), state_->context->device());
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_as_hf_error("OpenCL push-pull on " + state_->context->info().describe());
  }
}

PushPullOpenCl::~PushPullOpenCl() = default;

PushPullResult PushPullOpenCl::fill(int width, int height, int channels, float* values, std::uint8_t* mask,
                                    const PushPullOptions& options) {
  long samples = 0;
  PushPullResult result = push_pull_prepare(width, height, channels, values, mask, &samples);
  if (!push_pull_filled(result.status)) return result;
  const std::vector<PushPullLevel> levels = push_pull_levels(width, height, options);
  const int L = int(levels.size()) - 1;
  try {
    const cl::Context& ctx = state_->context->context();
    std::vector<cl::Buffer> level_values, level_masks;
    for (const PushPullLevel& level : levels) {
      const size_t n = size_t(level.width) * level.height;
      level_values.emplace_back(ctx, CL_MEM_READ_WRITE, n * channels * sizeof(float));
      level_masks.emplace_back(ctx, CL_MEM_READ_WRITE, n);
    }
    cl::CommandQueue& q = state_->queue;
    const size_t n0 = size_t(width) * height;
    q.enqueueWriteBuffer(level_values[0], CL_FALSE, 0, n0 * channels * sizeof(float), values);
    q.enqueueWriteBuffer(level_masks[0], CL_FALSE, 0, n0, mask);
    // Both kernels take (level l values, mask, width, height, channels, level l + 1 values, mask).
    auto enqueue = [&](cl::Kernel& k, int l, const cl::NDRange& range) {
      k.setArg(0, level_values[l]);
      k.setArg(1, level_masks[l]);
      k.setArg(2, levels[l].width);
      k.setArg(3, levels[l].height);
      k.setArg(4, channels);
      k.setArg(5, level_values[l + 1]);
      k.setArg(6, level_masks[l + 1]);
      q.enqueueNDRangeKernel(k, cl::NullRange, range);
    };
    for (int l = 0; l < L; ++l) enqueue(state_->push, l, cl::NDRange(levels[l + 1].width, levels[l + 1].height));
    for (int l = L - 1; l >= 0; --l) enqueue(state_->pull, l, cl::NDRange(levels[l].width, levels[l].height));
    q.enqueueReadBuffer(level_values[0], CL_FALSE, 0, n0 * channels * sizeof(float), values);
    q.enqueueReadBuffer(level_masks[0], CL_TRUE, 0, n0, mask);
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_as_hf_error("OpenCL push-pull on " + state_->context->info().describe());
  }
  result.levels = L;
  push_pull_finish(mask, long(width) * height, samples, &result);
  return result;
}

}  // namespace hf::opencl
