#include "registration/opencl/device_pyramid.h"

#include <cmath>
#include <utility>
#include <vector>

#include "core/error.h"
#include "core/filters.h"
#include "core/normals.h"
#include "core/pyramid.h"

namespace hf::opencl {

namespace {

size_t round_up(size_t n, size_t m) { return (n + m - 1) / m * m; }

// A 2-D kernel over w x h items in 8 x 8 groups (a fixed size: PoCL compiles a kernel per work-group size).
void run_2d(cl::CommandQueue& q, const cl::Kernel& k, int w, int h) {
  q.enqueueNDRangeKernel(k, cl::NullRange, cl::NDRange(round_up(size_t(w), 8), round_up(size_t(h), 8)),
                         cl::NDRange(8, 8));
}

template <class... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  cl_uint i = 0;
  (kernel.setArg(i++, args), ...);
}

void check_size(int width, int height, const PinholeCamera& camera, const char* what) {
  if (width != camera.width || height != camera.height)
    throw Error(std::string("frame pyramid (device): ") + what + " is " + std::to_string(width) + "x" +
                std::to_string(height) + " but the camera is " + std::to_string(camera.width) + "x" +
                std::to_string(camera.height));
}

}  // namespace

struct DeviceFramePyramid::Impl {
  std::shared_ptr<Context> ctx;
  cl::CommandQueue queue;
  cl::Kernel keep, down_depth, down_gaussian, bilateral, vertices, normals, intensity, gradients, model_depth;
  // The device buffers of the maps just read back, published when the queue has finished (Context::publish).
  struct Published {
    FramePyramidLevel* level;
    const void* host;
    size_t bytes;
    cl::Buffer buffer;
  };
  std::vector<Published> published;

  template <class T>
  void read_back(const cl::Buffer& src, Image<T>& dst, FramePyramidLevel& level, bool blocking) {
    const size_t bytes = dst.size() * sizeof(T);
    queue.enqueueReadBuffer(src, blocking ? CL_TRUE : CL_FALSE, 0, bytes, dst.data());
    published.push_back({&level, dst.data(), bytes, src});
  }
  // Every read finished: the buffers hold what the host images hold, and nothing writes them again (each build
  // allocates its own), so they become the images' device copies.
  void publish_all() {
    queue.finish();
    for (const Published& p : published)
      p.level->device_copies.add(p.host, ctx->publish(p.host, p.bytes, p.buffer));
    published.clear();
  }
  // Runs one build's commands, then publishes what it read back; on any failure nothing is published (the levels'
  // images are not what the buffers hold) and an OpenCL error becomes hf::Error naming `stage` and the device.
  template <class Commands>
  void run_and_publish(const char* stage, Commands&& commands) {
    try {
      commands();
      publish_all();
    } catch (const Error&) {
      published.clear();
      throw;
    } catch (...) {
      published.clear();
      rethrow_as_hf_error(std::string(stage) + " on " + ctx->info().platform_name + " / " + ctx->info().device_name);
    }
  }
  // Vertices and normals of a w x h level from its depth, read back into `level`.
  void geometry(const cl::Buffer& d, int w, int h, FramePyramidLevel& level) {
    const NormalParams np;
    const size_t n = size_t(w) * size_t(h);
    cl::Buffer v = buffer(n * sizeof(hf_float4)), nn = buffer(n * sizeof(hf_float4));
    hf_intrinsics K = level.camera.kernel_intrinsics();
    K.width = w, K.height = h;
    set_args(vertices, d, K, v);
    run_2d(queue, vertices, w, h);
    set_args(normals, v, w, h, np.max_depth_jump_ratio, nn);
    run_2d(queue, normals, w, h);
    level.vertices = VertexMap(w, h);
    level.normals = NormalMap(w, h);
    read_back(v, level.vertices, level, false);
    read_back(nn, level.normals, level, true);
  }

  cl::Buffer buffer(size_t bytes, cl_mem_flags flags = CL_MEM_READ_WRITE) const {
    return cl::Buffer(ctx->context(), flags, bytes == 0 ? 1 : bytes);
  }
  cl::Buffer half_depth(const cl::Buffer& src, int w, int h, float max_diff_m) {
    cl::Buffer dst = buffer(size_t(w / 2) * size_t(h / 2) * sizeof(float));
    set_args(down_depth, src, w, h, max_diff_m, dst);
    run_2d(queue, down_depth, w / 2, h / 2);
    return dst;
  }
  cl::Buffer half_gaussian(const cl::Buffer& src, int w, int h) {
    cl::Buffer dst = buffer(size_t(w / 2) * size_t(h / 2) * sizeof(float));
    set_args(down_gaussian, src, w, h, dst);
    run_2d(queue, down_gaussian, w / 2, h / 2);
    return dst;
  }
};

DeviceFramePyramid::DeviceFramePyramid(std::shared_ptr<Context> context) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.ctx = std::move(context);
  if (!m.ctx) throw Error("DeviceFramePyramid: no OpenCL context");
  try {
    cl::Program p = m.ctx->program("pyramid", pyramid_program_source(), "-cl-fp32-correctly-rounded-divide-sqrt");
    m.queue = cl::CommandQueue(m.ctx->context(), m.ctx->device());
    m.keep = cl::Kernel(p, "hf_pyr_keep_depth");
    m.down_depth = cl::Kernel(p, "hf_pyr_down_depth");
    m.down_gaussian = cl::Kernel(p, "hf_pyr_down_gaussian");
    m.bilateral = cl::Kernel(p, "hf_pyr_bilateral");
    m.vertices = cl::Kernel(p, "hf_pyr_vertices");
    m.normals = cl::Kernel(p, "hf_pyr_normals");
    m.intensity = cl::Kernel(p, "hf_pyr_intensity");
    m.gradients = cl::Kernel(p, "hf_pyr_gradients");
    m.model_depth = cl::Kernel(p, "hf_pyr_model_depth");
  } catch (const Error&) {
    throw;
  } catch (...) {
    rethrow_as_hf_error("frame pyramid on " + m.ctx->info().describe());
  }
}

DeviceFramePyramid::~DeviceFramePyramid() = default;

std::string DeviceFramePyramid::device_name() const {
  return impl_->ctx->info().platform_name + " / " + impl_->ctx->info().device_name;
}

FramePyramid DeviceFramePyramid::build(const DepthImage& depth, const ColorImage* color, const PinholeCamera& camera,
                                       const FramePyramidOptions& options) {
  if (options.levels < 1) throw Error("frame pyramid: levels must be >= 1, got " + std::to_string(options.levels));
  if (options.first_level < 0 || options.first_level > 4)
    throw Error("frame pyramid: first_level must be in [0, 4], got " + std::to_string(options.first_level));
  if (options.fill_holes_levels != 0)
    throw Error("frame pyramid (device): fill_holes_levels (push-pull) has no device kernel; build on the cpu");
  check_size(depth.width(), depth.height(), camera, "the depth image");
  if (color != nullptr) check_size(color->width(), color->height(), camera, "the colour image");
  // The C++ steps' size rule (pyr_down_*: at least 2 x 2 to halve), checked before anything is enqueued.
  for (int l = 0, w = camera.width, h = camera.height; l + 1 < options.first_level + options.levels; ++l) {
    if (w < 2 || h < 2)
      throw Error("frame pyramid (device): a " + std::to_string(w) + "x" + std::to_string(h) +
                  " image cannot be halved (need at least 2x2)");
    w /= 2, h /= 2;
  }
  Impl& m = *impl_;
  const float max_diff_m = 3.0f * kDepthPyramidSigmaR_m;  // build_depth_pyramid's and pyr_down_depth's default
  FramePyramid pyramid;
  pyramid.levels.resize(size_t(options.levels));
  m.run_and_publish("frame pyramid", [&] {
    cl::CommandQueue& q = m.queue;
    int w = depth.width(), h = depth.height();
    cl::Buffer raw = m.buffer(depth.size() * sizeof(float), CL_MEM_READ_ONLY);
    q.enqueueWriteBuffer(raw, CL_FALSE, 0, depth.size() * sizeof(float), depth.data());
    cl::Buffer d = m.buffer(depth.size() * sizeof(float));
    set_args(m.keep, raw, w, h, options.min_depth_m, options.max_depth_m, d);
    run_2d(q, m.keep, w, h);
    for (int l = 0; l < options.first_level; ++l, w /= 2, h /= 2) d = m.half_depth(d, w, h, max_diff_m);
    if (options.bilateral_filter) {
      const BilateralParams bp;
      const int radius = bp.radius_px > 0 ? bp.radius_px : int(std::ceil(2.0f * bp.sigma_s_px));
      cl::Buffer filtered = m.buffer(size_t(w) * size_t(h) * sizeof(float));
      set_args(m.bilateral, d, w, h, radius, 1.0f / (2.0f * bp.sigma_s_px * bp.sigma_s_px),
               1.0f / (2.0f * bp.sigma_r_m * bp.sigma_r_m), filtered);
      run_2d(q, m.bilateral, w, h);
      d = filtered;
    }
    for (int l = 0; l < options.levels; ++l) {
      FramePyramidLevel& level = pyramid.levels[size_t(l)];
      level.camera = camera.scaled(options.first_level + l);
      if (l > 0) {
        d = m.half_depth(d, w, h, max_diff_m);
        w /= 2, h /= 2;
      }
      m.geometry(d, w, h, level);
    }
    if (color != nullptr) {
      w = color->width(), h = color->height();
      cl::Buffer rgb = m.buffer(color->size() * 3, CL_MEM_READ_ONLY);
      static_assert(sizeof(Rgb8) == 3, "packed rgb");
      q.enqueueWriteBuffer(rgb, CL_FALSE, 0, color->size() * 3, color->data());
      cl::Buffer g = m.buffer(color->size() * sizeof(float));
      set_args(m.intensity, rgb, w, h, g);
      run_2d(q, m.intensity, w, h);
      for (int l = 0; l < options.first_level; ++l, w /= 2, h /= 2) g = m.half_gaussian(g, w, h);
      for (int l = 0; l < options.levels; ++l) {
        if (l > 0) {
          g = m.half_gaussian(g, w, h);
          w /= 2, h /= 2;
        }
        FramePyramidLevel& level = pyramid.levels[size_t(l)];
        const size_t n = size_t(w) * size_t(h);
        cl::Buffer gx = m.buffer(n * sizeof(float)), gy = m.buffer(n * sizeof(float));
        set_args(m.gradients, g, w, h, gx, gy);
        run_2d(q, m.gradients, w, h);
        level.intensity = Image<float>(w, h);
        level.grad_x = Image<float>(w, h);
        level.grad_y = Image<float>(w, h);
        m.read_back(g, level.intensity, level, false);
        m.read_back(gx, level.grad_x, level, false);
        m.read_back(gy, level.grad_y, level, true);
      }
    }
  });
  return pyramid;
}

FramePyramid DeviceFramePyramid::build_model(const VertexMap& vertices, const NormalMap& normals,
                                             const PinholeCamera& camera, int levels) {
  if (levels < 1) throw Error("frame pyramid: levels must be >= 1, got " + std::to_string(levels));
  check_size(vertices.width(), vertices.height(), camera, "the vertex map");
  check_size(normals.width(), normals.height(), camera, "the normal map");
  for (int l = 0, w = camera.width, h = camera.height; l + 1 < levels; ++l, w /= 2, h /= 2) {
    if (w < 2 || h < 2)
      throw Error("frame pyramid (device): a " + std::to_string(w) + "x" + std::to_string(h) +
                  " image cannot be halved (need at least 2x2)");
  }
  Impl& m = *impl_;
  const float max_diff_m = 3.0f * kDepthPyramidSigmaR_m;  // build_depth_pyramid's default
  FramePyramid pyramid;
  pyramid.levels.resize(size_t(levels));
  m.run_and_publish("model pyramid", [&] {
    cl::CommandQueue& q = m.queue;
    int w = camera.width, h = camera.height;
    const size_t n = size_t(w) * size_t(h), bytes = n * sizeof(hf_float4);
    // The maps' device copies where they have them (the device raycast's), else one upload each.
    auto on_device = [&](const Image<hf_float4>& map) {
      cl::Buffer b = m.ctx->resident(map.data(), bytes);
      if (b() != nullptr) return b;
      b = m.buffer(bytes, CL_MEM_READ_ONLY);
      q.enqueueWriteBuffer(b, CL_FALSE, 0, bytes, map.data());
      return b;
    };
    const cl::Buffer v0 = on_device(vertices), n0 = on_device(normals);
    FramePyramidLevel& level0 = pyramid.levels[0];
    level0.camera = camera;
    level0.vertices = vertices;  // host copies; their device copies are the same buffers
    level0.normals = normals;
    m.published.push_back({&level0, level0.vertices.data(), bytes, v0});
    m.published.push_back({&level0, level0.normals.data(), bytes, n0});
    if (levels > 1) {
      cl::Buffer d = m.buffer(n * sizeof(float));
      set_args(m.model_depth, v0, w, h, d);
      run_2d(q, m.model_depth, w, h);
      for (int l = 1; l < levels; ++l) {
        FramePyramidLevel& level = pyramid.levels[size_t(l)];
        level.camera = camera.scaled(l);
        d = m.half_depth(d, w, h, max_diff_m);
        w /= 2, h /= 2;
        m.geometry(d, w, h, level);
      }
    }
  });
  return pyramid;
}

}  // namespace hf::opencl
