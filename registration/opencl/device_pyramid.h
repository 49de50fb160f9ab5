// build_frame_pyramid (registration/frame_pyramid.h) on an OpenCL device (issue 20: the frame pyramid beside the
// map and the raycast on the device). Each step is a kernel around the per-pixel function of
// core/kernels/image_kernels.h that the C++ step calls (registration/opencl/pyramid.cl).
//
//   hf::opencl::DeviceFramePyramid builder;                         // Context::shared() unless given
//   hf::FramePyramid p = builder.build(depth, &colour, camera, options);
//
// Same inputs, outputs and errors as build_frame_pyramid, except fill_holes_levels > 0 (push-pull has no device
// kernel): hf::Error. The levels come back to host memory for the CPU stages, and each level's maps stay on the
// device as their published copies (core/device_copy.h, FramePyramidLevel::device_copies), which the OpenCL
// reduction backend on the same context binds instead of uploading them again. Agreement
// with the C++ pyramid: the depth steps, vertices, normals, intensity and gradients are the same float
// operations (FP_CONTRACT OFF, correctly rounded division); the bilateral filter's exp is the device's, within a
// few ulps of the C++ one, so filtered depths differ by float rounding (on PoCL, the room at 320x240: vertices
// within 1.2e-6 m, normals within 1e-4, everything else equal bit for bit; tests/registration/
// test_opencl_backend.cpp). Thread-safety: one build at a time per object (own command queue).
#pragma once

#include <memory>
#include <string>

#include "core/camera.h"
#include "core/image.h"
#include "registration/frame_pyramid.h"
#include "core/opencl/opencl_context.h"

namespace hf::opencl {

class DeviceFramePyramid {
 public:
  explicit DeviceFramePyramid(std::shared_ptr<Context> context = Context::shared());
  ~DeviceFramePyramid();
  DeviceFramePyramid(const DeviceFramePyramid&) = delete;
  DeviceFramePyramid& operator=(const DeviceFramePyramid&) = delete;

  FramePyramid build(const DepthImage& depth, const ColorImage* color, const PinholeCamera& camera,
                     const FramePyramidOptions& options = {});
  // build_model_pyramid (registration/frame_pyramid.h, no intensity) on the device, from model maps that have a
  // copy here (the device raycast's, DeviceVoxelGrid::raycast) or are uploaded once otherwise: level 0 holds
  // copies of the maps (published with the same device copies), the coarser levels are derived on the device.
  // Same errors as build_model_pyramid; agreement with it as for build() (same float operations).
  FramePyramid build_model(const VertexMap& vertices, const NormalMap& normals, const PinholeCamera& camera,
                           int levels = 3);
  std::string device_name() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// pyramid.cl with the shared headers inlined (embed_opencl.cmake, registration/opencl/CMakeLists.txt).
std::string_view pyramid_program_source();

}  // namespace hf::opencl
