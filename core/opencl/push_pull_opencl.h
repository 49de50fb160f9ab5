// The push-pull fill (core/push_pull.h) on an OpenCL device: the same contract, statuses and in-place update as
// hf::push_pull_fill, computed by core/opencl/push_pull.cl over the shared per-pixel maths of
// core/kernels/push_pull_kernels.h. Level 0 is prepared on the host by the same kernel function, so the dropped
// non-finite count is exact; the result equals the C++ one to float rounding (division is correctly rounded on
// both; tests/core/test_push_pull.cpp holds them to 1e-6 relative).
//
// The device, context and program cache are core/opencl/opencl_context.h's (HF_OPENCL_DEVICE chooses the
// device). Errors: hf::Error when no OpenCL platform is installed or a call fails (message names the call).
// Thread-safety: one PushPullOpenCl per thread (it owns its queue); several may share a Context.
#pragma once

#include <cstdint>
#include <memory>

#include "core/push_pull.h"

namespace hf::opencl {

class Context;

class PushPullOpenCl {
 public:
  // context: nullptr = Context::shared().
  explicit PushPullOpenCl(std::shared_ptr<Context> context = nullptr);
  ~PushPullOpenCl();
  PushPullOpenCl(const PushPullOpenCl&) = delete;
  PushPullOpenCl& operator=(const PushPullOpenCl&) = delete;

  PushPullResult fill(int width, int height, int channels, float* values, std::uint8_t* mask,
                      const PushPullOptions& options = {});

 private:
  struct State;
  std::unique_ptr<State> state_;
};

}  // namespace hf::opencl
