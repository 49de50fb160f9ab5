#include "fusion/opencl/device_voxel_grid.h"

#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <memory>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

#include "fusion/kernels/block_hash.h"
#include "fusion/kernels/raycast_kernels.h"
#include "core/opencl/opencl_context.h"
#include "core/timing.h"

namespace hf::opencl {
// fusion/opencl/integrate.cl with the shared headers inlined (embed_opencl.cmake, fusion/opencl/CMakeLists.txt).
std::string_view fusion_program_source();
}  // namespace hf::opencl

namespace hf::fusion {

namespace {

// integrate.cl's counter indices and error bits.
enum Counter : int {
  kPoolNext = 0, kEmitted = 1, kMissing = 2, kVisible = 3, kError = 4, kUpdated = 5, kPixels = 6, kCreated = 7,
  kInView = 8, kErrorKey = 9, kCounters = 16
};
constexpr std::uint32_t kErrorPool = 1, kErrorProbe = 2, kErrorList = 4;
constexpr int kFrameConstants = 34;  // HF_F_COUNT
constexpr size_t kUpdateGroup = 64;  // work-items per group of the 1-D kernels (divides 512)

using Entry = hf_block_entry;  // fusion/kernels/block_hash.h
static_assert(sizeof(Entry) == 16, "hf_block_entry");

size_t round_up(size_t n, size_t m) { return (n + m - 1) / m * m; }

// A 1-D kernel over n items (the kernels ignore items >= n) in groups of kUpdateGroup: a fixed work-group size, so
// a driver that compiles a kernel per work-group size (PoCL) does it once, not for every frame's item count.
void enqueue_1d(cl::CommandQueue& q, const cl::Kernel& kernel, size_t n) {
  q.enqueueNDRangeKernel(kernel, cl::NullRange, cl::NDRange(round_up(n, kUpdateGroup)), cl::NDRange(kUpdateGroup));
}

// kernel.setArg(first, args[0]), setArg(first + 1, args[1]), ...
template <class... Args>
void set_args_from(cl::Kernel& kernel, cl_uint first, const Args&... args) {
  cl_uint i = first;
  (kernel.setArg(i++, args), ...);
}
template <class... Args>
void set_args(cl::Kernel& kernel, const Args&... args) {
  set_args_from(kernel, 0, args...);
}

}  // namespace

struct DeviceVoxelGrid::Impl {
  std::shared_ptr<opencl::Context> ctx;
  DeviceGridOptions options;
  bool fp64 = false;
  cl::Kernel band_ends, bands, find, create, block_frames, incidence, update, gather;
  cl::Kernel clear_range, range, regions, march, surface_free;
  cl::Buffer flags;  // per pool slot: VoxelBlockGrid::surface_free (uint 0/1), for the raycast's block skip
  // The raycast's buffers, per image size (mutable: raycast() is const on the map).
  cl::Buffer rc_constants, rc_near, rc_far, rc_depth, rc_vertices, rc_normals, rc_hits, rc_hints;
  cl::Buffer rc_regions;  // the region occupancy set, `entries` slots
  cl::Buffer rc_colour;   // 3 bytes per pixel
  // publish_map()'s copies: the map is not written while a holder keeps one.
  void check_map_unpublished(const char* what) const {
    if (ctx->published(table) || ctx->published(pool))
      throw Error(std::string("DeviceVoxelGrid::") + what +
                  ": the map's table and pool are published as a host grid's copy (publish_map) and must not change "
                  "while their holder keeps them: drop the copies first");
  }
  size_t rc_pixels = 0, rc_tiles = 0;
  DeviceVoxelGrid::RaycastTimes rc_times;
  size_t entries = 0;
  int shift = 0;
  cl::Buffer table, stamps, pool, visible, frames, counters, constants;
  // Per frame size: the images and the key lists.
  cl::Buffer depth, rgb, incidence_map, list, missing, ends, cells, ok;  // ends / cells / ok: per pixel
  cl::Buffer staging, staging_entries;  // hf_gather_blocks' output, staging_blocks blocks
  size_t staging_blocks = 0;
  size_t pixels = 0, list_capacity = 0;
  std::uint32_t pool_next = 0, frame_stamp = 0, last_visible = 0;

  std::string where() const { return "integrate on " + ctx->info().platform_name + " / " + ctx->info().device_name; }

  std::array<std::uint32_t, kCounters> read_counters() {
    std::array<std::uint32_t, kCounters> c{};
    ctx->queue().enqueueReadBuffer(counters, CL_TRUE, 0, sizeof(c), c.data());
    return c;
  }

  void ensure_frame_buffers(size_t n_pixels, double truncation_vox) {
    if (n_pixels <= pixels) return;
    const cl::Context& c = ctx->context();
    depth = cl::Buffer(c, CL_MEM_READ_ONLY, n_pixels * sizeof(float));
    rgb = cl::Buffer(c, CL_MEM_READ_ONLY, n_pixels * 3);
    incidence_map = cl::Buffer(c, CL_MEM_READ_WRITE, n_pixels * sizeof(float));
    ends = cl::Buffer(c, CL_MEM_READ_WRITE, n_pixels * 6 * (fp64 ? sizeof(double) : sizeof(float)));
    cells = cl::Buffer(c, CL_MEM_READ_WRITE, n_pixels * 6 * sizeof(cl_int));
    ok = cl::Buffer(c, CL_MEM_READ_WRITE, n_pixels);
    // A ray's band spans 2 mu = truncation_vox / 4 blocks, so it crosses at most ceil(that) + 1 cells per axis and
    // its walk takes at most their sum + 1 steps: the list holds every pixel's worst case.
    const size_t per_pixel = 3 * (size_t(std::ceil(truncation_vox / 4.0)) + 1) + 1;
    list_capacity = n_pixels * per_pixel;
    list = cl::Buffer(c, CL_MEM_READ_WRITE, list_capacity * sizeof(std::uint64_t));
    missing = cl::Buffer(c, CL_MEM_READ_WRITE, list_capacity * sizeof(std::uint32_t));
    pixels = n_pixels;
  }

  // Copies blocks into grid: wanted[i]'s voxels are voxels[i * 512, (i + 1) * 512).
  static size_t copy_into(VoxelBlockGrid& grid, const std::vector<Entry>& wanted, const std::vector<Voxel>& voxels) {
    std::vector<size_t> order(wanted.size());
    for (size_t i = 0; i < order.size(); ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](size_t i, size_t j) {
      const Entry &a = wanted[i], &b = wanted[j];
      if (a.z != b.z) return a.z < b.z;
      if (a.y != b.y) return a.y < b.y;
      return a.x < b.x;
    });
    for (size_t i : order) {
      const Entry& e = wanted[i];
      std::uint8_t* flag = nullptr;
      VoxelBlock* block = grid.allocate({e.x, e.y, e.z}, nullptr, &flag);
      std::memcpy(block->voxels.data(), voxels.data() + i * HF_VOXELS_PER_BLOCK, sizeof(VoxelBlock));
      *flag = block_is_surface_free(*block) ? 1 : 0;
    }
    return order.size();
  }

};

DeviceVoxelGrid::DeviceVoxelGrid(const VolumeParams& params, std::shared_ptr<opencl::Context> context,
                                 const DeviceGridOptions& options)
    : params_(params), impl_(std::make_unique<Impl>()) {
  params_.validate();
  if (options.max_probe < 1) throw Error("DeviceGridOptions::max_probe must be >= 1, got " +
                                         std::to_string(options.max_probe));
  Impl& m = *impl_;
  m.options = options;
  m.ctx = context ? std::move(context) : opencl::Context::shared();
  try {
    const cl::Device& device = m.ctx->device();
    const size_t pool_bytes = params_.capacity_blocks * sizeof(VoxelBlock);
    m.entries = std::bit_ceil(std::max<size_t>(16, 2 * params_.capacity_blocks));
    m.shift = 64 - std::countr_zero(m.entries);
    const cl_ulong max_alloc = device.getInfo<CL_DEVICE_MAX_MEM_ALLOC_SIZE>();
    const cl_ulong global = device.getInfo<CL_DEVICE_GLOBAL_MEM_SIZE>();
    const size_t table_bytes = m.entries * (sizeof(Entry) + sizeof(std::uint32_t));
    if (pool_bytes > max_alloc || pool_bytes + table_bytes > global) {
      std::ostringstream msg;
      msg << m.where() << ": a pool of " << params_.capacity_blocks << " blocks (" << pool_bytes / (1024 * 1024)
          << " MiB) does not fit the device (largest allocation " << max_alloc / (1024 * 1024) << " MiB, memory "
          << global / (1024 * 1024) << " MiB); lower VolumeParams::capacity_blocks (--capacity-blocks)";
      throw DeviceMemoryError(msg.str());
    }
    m.fp64 = m.ctx->info().has_fp64;
    std::string build = "-cl-fp32-correctly-rounded-divide-sqrt";
    if (m.fp64) build += " -DHF_FP64=1";
    cl::Program program =
        m.ctx->program(m.fp64 ? "fusion-fp64" : "fusion-fp32", opencl::fusion_program_source(), build);
    m.band_ends = cl::Kernel(program, "hf_fusion_band_ends");
    m.bands = cl::Kernel(program, "hf_fusion_bands");
    m.find = cl::Kernel(program, "hf_fusion_find");
    m.create = cl::Kernel(program, "hf_fusion_create");
    m.block_frames = cl::Kernel(program, "hf_fusion_block_frames");
    m.incidence = cl::Kernel(program, "hf_point_to_plane");
    m.update = cl::Kernel(program, "hf_fusion_update");
    m.gather = cl::Kernel(program, "hf_gather_blocks");
    m.clear_range = cl::Kernel(program, "hf_raycast_clear_range");
    m.range = cl::Kernel(program, "hf_raycast_range");
    m.march = cl::Kernel(program, "hf_raycast_march");
    m.regions = cl::Kernel(program, "hf_raycast_regions");
    m.surface_free = cl::Kernel(program, "hf_fusion_surface_free");
    const cl::Context& c = m.ctx->context();
    m.table = cl::Buffer(c, CL_MEM_READ_WRITE, m.entries * sizeof(Entry));
    m.stamps = cl::Buffer(c, CL_MEM_READ_WRITE, m.entries * sizeof(std::uint32_t));
    m.pool = cl::Buffer(c, CL_MEM_READ_WRITE, pool_bytes);
    m.visible = cl::Buffer(c, CL_MEM_READ_WRITE, params_.capacity_blocks * sizeof(std::uint32_t));
    m.frames = cl::Buffer(c, CL_MEM_READ_WRITE, params_.capacity_blocks * 4 * sizeof(float));
    m.counters = cl::Buffer(c, CL_MEM_READ_WRITE, kCounters * sizeof(std::uint32_t));
    m.constants = cl::Buffer(c, CL_MEM_READ_ONLY, kFrameConstants * (m.fp64 ? sizeof(double) : sizeof(float)));
    m.rc_constants = cl::Buffer(c, CL_MEM_READ_ONLY, kFrameConstants * (m.fp64 ? sizeof(double) : sizeof(float)));
    m.rc_hits = cl::Buffer(c, CL_MEM_READ_WRITE, sizeof(cl_uint));
    m.rc_regions = cl::Buffer(c, CL_MEM_READ_WRITE, m.entries * sizeof(cl_uint));
    m.ctx->queue().enqueueFillBuffer(m.pool, std::uint32_t(0), 0, pool_bytes);
    m.flags = cl::Buffer(c, CL_MEM_READ_WRITE, params_.capacity_blocks * sizeof(std::uint32_t));
    m.ctx->queue().enqueueFillBuffer(m.flags, std::uint32_t(0), 0, params_.capacity_blocks * sizeof(std::uint32_t));
  } catch (const Error&) {
    throw;
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
  clear();
}

DeviceVoxelGrid::~DeviceVoxelGrid() = default;

std::string DeviceVoxelGrid::device_name() const {
  return impl_->ctx->info().platform_name + " / " + impl_->ctx->info().device_name;
}

void DeviceVoxelGrid::clear() {
  Impl& m = *impl_;
  m.check_map_unpublished("clear");
  try {
    cl::CommandQueue& q = m.ctx->queue();
    q.enqueueFillBuffer(m.table, std::uint32_t(0), 0, m.entries * sizeof(Entry));
    q.enqueueFillBuffer(m.stamps, std::uint32_t(0), 0, m.entries * sizeof(std::uint32_t));
    // A block is zero (unobserved) when it is created: slots are handed out from 0 up, so only the slots handed
    // out since the pool was zeroed (all of it, in the constructor) need zeroing again.
    if (m.pool_next > 0) {
      q.enqueueFillBuffer(m.pool, std::uint32_t(0), 0, m.pool_next * sizeof(VoxelBlock));
      q.enqueueFillBuffer(m.flags, std::uint32_t(0), 0, m.pool_next * sizeof(std::uint32_t));  // never skip
    }
    q.finish();
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
  m.pool_next = 0;
  m.frame_stamp = 0;
  m.last_visible = 0;
}

size_t DeviceVoxelGrid::block_count() const { return impl_->pool_next; }

IntegrateStats DeviceVoxelGrid::integrate(const DepthImage& depth, const ColorImage& colour,
                                          const PinholeCamera& camera, const SE3& T_world_camera,
                                          const IntegrateParams& params) {
  detail::check_frame_sizes(depth, colour, camera);
  if (params.truncation_depth_ref_m > 0.0f || params.weight_depth_ref_m > 0.0f)
    throw Error("DeviceVoxelGrid::integrate: integrate.truncation_depth_ref_m and weight_depth_ref_m are on the CPU "
                "map only");
  Impl& m = *impl_;
  m.check_map_unpublished("integrate");
  IntegrateStats stats;
  m.last_visible = 0;
  const size_t n_pixels = size_t(depth.width()) * size_t(depth.height());
  if (n_pixels == 0) {
    stats.blocks_total = m.pool_next;
    return stats;
  }
  std::array<std::uint32_t, kCounters> c{};
  try {
    cl::CommandQueue& q = m.ctx->queue();
    auto t0 = std::chrono::steady_clock::now();
    m.ensure_frame_buffers(n_pixels, params_.truncation_vox);
    // The frame's constants in integrate.cl's order, in the device's real type.
    const Eigen::Matrix3d R_wc = T_world_camera.rotation();
    const Eigen::Vector3d t_wc = T_world_camera.translation();
    const SE3 T_camera_world = T_world_camera.inverse();
    const Eigen::Matrix3d R_cw = T_camera_world.rotation();
    const Eigen::Vector3d t_cw = T_camera_world.translation();
    std::array<double, kFrameConstants> f{};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) {
        f[size_t(3 * i + j)] = R_wc(i, j);
        f[size_t(20 + 3 * i + j)] = R_cw(i, j);
      }
      f[size_t(9 + i)] = t_wc[i];
      f[size_t(29 + i)] = t_cw[i];
    }
    f[12] = 1.0 / params_.block_m();
    f[13] = params_.truncation_m();
    f[14] = params.min_depth_m;
    f[15] = params.max_depth_m;
    f[16] = camera.fx, f[17] = camera.fy, f[18] = camera.cx, f[19] = camera.cy;
    f[32] = params_.voxel_m;
    f[33] = params_.block_m();
    if (m.fp64) {
      q.enqueueWriteBuffer(m.constants, CL_FALSE, 0, sizeof(f), f.data());
    } else {
      std::array<float, kFrameConstants> f32{};
      for (size_t i = 0; i < f.size(); ++i) f32[i] = float(f[i]);
      q.enqueueWriteBuffer(m.constants, CL_TRUE, 0, sizeof(f32), f32.data());
    }
    q.enqueueWriteBuffer(m.depth, CL_FALSE, 0, n_pixels * sizeof(float), depth.data());
    c[kPoolNext] = m.pool_next;
    q.enqueueWriteBuffer(m.counters, CL_FALSE, 0, sizeof(c), c.data());
    ++m.frame_stamp;

    // Phase 1: bands, look-up, creation.
    const int W = depth.width(), H = depth.height();
    set_args(m.band_ends, m.depth, W, H, m.constants, m.ends, m.cells, m.ok);
    q.enqueueNDRangeKernel(m.band_ends, cl::NullRange, cl::NDRange(size_t(W), size_t(H)));
    set_args(m.bands, m.ends, m.cells, m.ok, W, H, m.list, cl_uint(m.list_capacity), m.counters);
    q.enqueueNDRangeKernel(m.bands, cl::NullRange, cl::NDRange(size_t(W), size_t(H)));
    c = m.read_counters();
    if (c[kError] & kErrorList) throw Error(m.where() + ": the frame's block list overflowed (internal error)");
    const cl_uint emitted = c[kEmitted];
    stats.pixels_used = c[kPixels];
    if (emitted > 0) {
      const cl_uint mask = cl_uint(m.entries - 1);
      set_args(m.find, m.list, emitted, m.table, mask, m.shift, m.options.max_probe, m.stamps,
               cl_uint(m.frame_stamp), m.visible, m.missing, m.counters);
      enqueue_1d(q, m.find, emitted);
      set_args(m.create, m.list, m.missing, m.table, mask, m.shift, m.options.max_probe, m.stamps,
               cl_uint(m.frame_stamp), m.visible, cl_uint(params_.capacity_blocks), m.counters);
      q.enqueueNDRangeKernel(m.create, cl::NullRange, cl::NDRange(1));
      c = m.read_counters();
    }
    m.pool_next = c[kPoolNext];
    stats.blocks_allocated = c[kCreated];
    stats.allocate_ms = ms_since(t0);
    if (c[kError] & (kErrorPool | kErrorProbe)) {
      const int x = int(c[kErrorKey]), y = int(c[kErrorKey + 1]), z = int(c[kErrorKey + 2]);
      std::ostringstream msg;
      if (c[kError] & kErrorPool)
        msg << "voxel block pool full on the device (" << device_name() << "): capacity " << params_.capacity_blocks
            << " blocks (" << params_.capacity_blocks * sizeof(VoxelBlock) / (1024 * 1024)
            << " MiB) reached while allocating block (" << x << ", " << y << ", " << z
            << "); raise VolumeParams::capacity_blocks (--capacity-blocks)";
      else
        msg << "voxel block hash on the device (" << device_name() << "): block (" << x << ", " << y << ", " << z
            << ") found no free entry within " << m.options.max_probe << " of its home (DeviceGridOptions::max_probe)";
      throw CapacityError(msg.str());
    }
    const cl_uint n_visible = c[kVisible];
    m.last_visible = n_visible;

    // Phase 2: the block frames, the point-to-plane factors, the voxels.
    auto t1 = std::chrono::steady_clock::now();
    if (n_visible > 0) {
      const hf_intrinsics K = camera.kernel_intrinsics();
      const float mu = float(params_.truncation_m());
      set_args(m.block_frames, m.visible, n_visible, m.table, m.constants, W, H, m.frames, m.counters);
      enqueue_1d(q, m.block_frames, n_visible);
      if (params.point_to_plane) {
        const auto t_inc = std::chrono::steady_clock::now();
        set_args(m.incidence, m.depth, K, mu, m.incidence_map);
        q.enqueueNDRangeKernel(m.incidence, cl::NullRange, cl::NDRange(size_t(W), size_t(H)));
        q.finish();
        stats.incidence_ms = ms_since(t_inc);
      }
      const bool has_rgb = !colour.empty();
      if (has_rgb) q.enqueueWriteBuffer(m.rgb, CL_FALSE, 0, n_pixels * 3, colour.data());
      const Eigen::Matrix3d& R = R_cw;
      cl_float4 steps[3];
      for (int a = 0; a < 3; ++a) {
        steps[a] = {{float(R(0, a) * params_.voxel_m), float(R(1, a) * params_.voxel_m),
                     float(R(2, a) * params_.voxel_m), 0.0f}};
      }
      set_args(m.update, m.visible, n_visible, m.table, m.frames, steps[0], steps[1], steps[2], m.depth,
               m.incidence_map, cl_int(params.point_to_plane ? 1 : 0), m.rgb, cl_int(has_rgb ? 1 : 0), K, mu,
               params_.max_weight, params.observation_weight, m.pool, m.counters);
      q.enqueueNDRangeKernel(m.update, cl::NullRange,
                             cl::NDRange(round_up(size_t(n_visible) * HF_VOXELS_PER_BLOCK, kUpdateGroup)),
                             cl::NDRange(kUpdateGroup));
      // The updated blocks' surface-free flags, as integrate() sets them on the host grid.
      set_args(m.surface_free, m.visible, n_visible, m.table, m.pool, m.flags, m.counters);
      enqueue_1d(q, m.surface_free, n_visible);
      c = m.read_counters();
    }
    stats.update_ms = ms_since(t1);
  } catch (const Error&) {
    throw;
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
  stats.voxels_updated = c[kUpdated];
  stats.blocks_visible = c[kInView];
  stats.blocks_total = m.pool_next;
  stats.memory_bytes = m.pool_next * sizeof(VoxelBlock) + m.entries * sizeof(Entry);
  return stats;
}

void DeviceVoxelGrid::check_host_grid(const VoxelBlockGrid& grid) const {
  const VolumeParams& g = grid.params();
  if (g.voxel_m != params_.voxel_m || g.truncation_vox != params_.truncation_vox || g.max_weight != params_.max_weight)
    throw Error("DeviceVoxelGrid: the host grid's voxel_m / truncation_vox / max_weight differ from the device map's");
}

void DeviceVoxelGrid::load(const VoxelBlockGrid& grid) {
  check_host_grid(grid);
  Impl& m = *impl_;
  m.check_map_unpublished("load");
  const auto blocks = grid.blocks();
  if (blocks.size() > params_.capacity_blocks)
    throw CapacityError("DeviceVoxelGrid::load: the host grid holds " + std::to_string(blocks.size()) +
                        " blocks, the device pool " + std::to_string(params_.capacity_blocks));
  // The table and the pool built here, in block_coords() order, with the device's probe bound.
  std::vector<Entry> table(m.entries, Entry{0, 0, 0, 0});
  std::vector<Voxel> pool(blocks.size() * HF_VOXELS_PER_BLOCK);
  std::vector<std::uint32_t> flags(blocks.size());
  for (size_t slot = 0; slot < blocks.size(); ++slot) {
    const BlockCoord& c = blocks[slot].first;
    flags[slot] = grid.surface_free(c) ? 1u : 0u;
    std::uint32_t e = hf_block_home(c.x, c.y, c.z, m.shift);
    int probe = 0;
    while (table[e].value != 0 && probe < m.options.max_probe) e = (e + 1) & std::uint32_t(m.entries - 1), ++probe;
    if (probe == m.options.max_probe)
      throw CapacityError("DeviceVoxelGrid::load: block (" + std::to_string(c.x) + ", " + std::to_string(c.y) + ", " +
                          std::to_string(c.z) + ") found no free entry within " +
                          std::to_string(m.options.max_probe) + " of its home (DeviceGridOptions::max_probe)");
    table[e] = Entry{c.x, c.y, c.z, std::uint32_t(slot + 1)};
    std::memcpy(pool.data() + slot * HF_VOXELS_PER_BLOCK, blocks[slot].second->voxels.data(), sizeof(VoxelBlock));
  }
  clear();
  try {
    cl::CommandQueue& q = m.ctx->queue();
    q.enqueueWriteBuffer(m.table, CL_FALSE, 0, table.size() * sizeof(Entry), table.data());
    if (!pool.empty()) {
      q.enqueueWriteBuffer(m.pool, CL_FALSE, 0, pool.size() * sizeof(Voxel), pool.data());
      q.enqueueWriteBuffer(m.flags, CL_FALSE, 0, flags.size() * sizeof(std::uint32_t), flags.data());
    }
    q.finish();
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
  m.pool_next = std::uint32_t(blocks.size());
}

DeviceCopies DeviceVoxelGrid::publish_map(const VoxelBlockGrid& mirror) const {
  check_host_grid(mirror);
  Impl& m = *impl_;
  m.ctx->queue().finish();  // the map holds what every enqueued write left in it
  DeviceCopies copies;
  const std::pair<size_t, const cl::Buffer*> parts[] = {{m.entries * sizeof(Entry), &m.table},
                                                         {params_.capacity_blocks * sizeof(VoxelBlock), &m.pool}};
  for (const auto& [bytes, buffer] : parts) copies.add(&mirror, m.ctx->publish(&mirror, bytes, *buffer));
  return copies;
}

size_t DeviceVoxelGrid::read_into(VoxelBlockGrid& grid) const {
  check_host_grid(grid);
  Impl& m = *impl_;
  try {
    // The table, then the pool's used prefix in one read (slots are handed out from 0 up).
    std::vector<Entry> entries(m.entries);
    m.ctx->queue().enqueueReadBuffer(m.table, CL_TRUE, 0, m.entries * sizeof(Entry), entries.data());
    std::vector<Voxel> pool(size_t(m.pool_next) * HF_VOXELS_PER_BLOCK);
    if (!pool.empty())
      m.ctx->queue().enqueueReadBuffer(m.pool, CL_TRUE, 0, pool.size() * sizeof(Voxel), pool.data());
    std::vector<Entry> wanted;
    std::vector<Voxel> voxels;
    for (const Entry& e : entries) {
      if (e.value == 0 || e.value > m.pool_next) continue;
      wanted.push_back(e);
      voxels.insert(voxels.end(), pool.begin() + std::ptrdiff_t(e.value - 1) * HF_VOXELS_PER_BLOCK,
                    pool.begin() + std::ptrdiff_t(e.value) * HF_VOXELS_PER_BLOCK);
    }
    return Impl::copy_into(grid, wanted, voxels);
  } catch (const Error&) {
    throw;
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
}

size_t DeviceVoxelGrid::read_last_frame_into(VoxelBlockGrid& grid) const {
  check_host_grid(grid);
  Impl& m = *impl_;
  const size_t n = m.last_visible;
  if (n == 0) return 0;
  try {
    cl::CommandQueue& q = m.ctx->queue();
    if (n > m.staging_blocks) {
      m.staging_blocks = std::max(n, 2 * m.staging_blocks);
      m.staging = cl::Buffer(m.ctx->context(), CL_MEM_READ_WRITE, m.staging_blocks * sizeof(VoxelBlock));
      m.staging_entries = cl::Buffer(m.ctx->context(), CL_MEM_READ_WRITE, m.staging_blocks * sizeof(Entry));
    }
    set_args(m.gather, m.visible, cl_uint(n), m.table, m.pool, m.staging, m.staging_entries);
    enqueue_1d(q, m.gather, n * HF_VOXELS_PER_BLOCK);
    std::vector<Entry> wanted(n);
    std::vector<Voxel> voxels(n * HF_VOXELS_PER_BLOCK);
    q.enqueueReadBuffer(m.staging, CL_FALSE, 0, voxels.size() * sizeof(Voxel), voxels.data());
    q.enqueueReadBuffer(m.staging_entries, CL_TRUE, 0, n * sizeof(Entry), wanted.data());
    return Impl::copy_into(grid, wanted, voxels);
  } catch (const Error&) {
    throw;
  } catch (...) {
    opencl::rethrow_as_hf_error(m.where());
  }
}

namespace {

// raycast.cl's hf_raycast_params.
struct RaycastParams {
  float R_wc[9];
  float o_vox[3];
  float mu_m, step_fraction, min_step_m, voxel_m, refine_tol_m, min_depth_m, max_depth_m;
  cl_int min_weight_raw;
  cl_int skip_blocks;
  cl_uint region_mask;
  cl_int colour;
  hf_intrinsics K;
};
static_assert(sizeof(RaycastParams) == 4 * (9 + 3 + 7 + 4) + sizeof(hf_intrinsics), "hf_raycast_params");

template <class T>
void ensure_image(Image<T>* img, int w, int h) {
  if (img->width() != w || img->height() != h) *img = Image<T>(w, h);
}

}  // namespace

DeviceVoxelGrid::RaycastTimes DeviceVoxelGrid::last_raycast_times() const { return impl_->rc_times; }

void DeviceVoxelGrid::raycast(const PinholeCamera& camera, const SE3& T_world_camera, const RaycastOptions& options,
                              RaycastResult* out) const {
  options.validate(camera);
  if (camera.width <= 0 || camera.height <= 0 || !(camera.fx > 0.0 && camera.fy > 0.0))
    throw Error("raycast: expected a camera with positive size and focal lengths, got " + camera.describe());
  if (!T_world_camera.is_finite()) throw Error("raycast: expected a finite T_world_camera");
  Impl& m = *impl_;
  const int W = camera.width, H = camera.height;
  const int TW = (W + 7) / 8, TH = (H + 7) / 8;
  const size_t n_pixels = size_t(W) * size_t(H), n_tiles = size_t(TW) * size_t(TH);
  out->device_copies.clear();  // the images are written below: their old copies no longer mirror them
  ensure_image(&out->depth, W, H);
  ensure_image(&out->vertices, W, H);
  ensure_image(&out->normals, W, H);
  ensure_image(&out->color, W, H);
  if (!options.color) std::fill(out->color.data(), out->color.data() + n_pixels, Rgb8{});
  if (options.shade)
    ensure_image(&out->shaded, W, H);
  else
    out->shaded = ColorImage();
  try {
    const cl::Context& c = m.ctx->context();
    cl::CommandQueue& q = m.ctx->queue();
    if (n_pixels > m.rc_pixels) {
      m.rc_depth = cl::Buffer(c, CL_MEM_WRITE_ONLY, n_pixels * sizeof(float));
      m.rc_vertices = cl::Buffer(c, CL_MEM_WRITE_ONLY, n_pixels * sizeof(hf_float4));
      m.rc_normals = cl::Buffer(c, CL_MEM_WRITE_ONLY, n_pixels * sizeof(hf_float4));
      m.rc_hints = cl::Buffer(c, CL_MEM_READ_ONLY, n_pixels * sizeof(float));
      m.rc_colour = cl::Buffer(c, CL_MEM_WRITE_ONLY, n_pixels * 3);
      m.rc_pixels = n_pixels;
    } else {
      // A published copy is never written again: while anyone keeps the last outputs as a copy (the result, or the
      // model pyramid's level 0 that shares them), the march writes new buffers.
      if (m.ctx->published(m.rc_depth)) m.rc_depth = cl::Buffer(c, CL_MEM_WRITE_ONLY, m.rc_pixels * sizeof(float));
      if (m.ctx->published(m.rc_vertices))
        m.rc_vertices = cl::Buffer(c, CL_MEM_WRITE_ONLY, m.rc_pixels * sizeof(hf_float4));
      if (m.ctx->published(m.rc_normals))
        m.rc_normals = cl::Buffer(c, CL_MEM_WRITE_ONLY, m.rc_pixels * sizeof(hf_float4));
    }
    if (n_tiles > m.rc_tiles) {
      m.rc_near = cl::Buffer(c, CL_MEM_READ_WRITE, n_tiles * sizeof(cl_uint));
      m.rc_far = cl::Buffer(c, CL_MEM_READ_WRITE, n_tiles * sizeof(cl_uint));
      m.rc_tiles = n_tiles;
    }
    const auto t0 = std::chrono::steady_clock::now();
    // The constants in integrate.cl's HF_F_* order (those the raycast reads), in the device's real type.
    const SE3 T_camera_world = T_world_camera.inverse();
    const Eigen::Matrix3d R_cw = T_camera_world.rotation();
    const Eigen::Vector3d t_cw = T_camera_world.translation();
    std::array<double, kFrameConstants> f{};
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) f[size_t(20 + 3 * i + j)] = R_cw(i, j);
      f[size_t(29 + i)] = t_cw[i];
    }
    f[14] = options.min_depth_m;
    f[15] = options.max_depth_m;
    f[16] = camera.fx, f[17] = camera.fy, f[18] = camera.cx, f[19] = camera.cy;
    f[32] = params_.voxel_m;
    f[33] = params_.block_m();
    if (m.fp64) {
      q.enqueueWriteBuffer(m.rc_constants, CL_TRUE, 0, sizeof(f), f.data());
    } else {
      std::array<float, kFrameConstants> f32{};
      for (size_t i = 0; i < f.size(); ++i) f32[i] = float(f[i]);
      q.enqueueWriteBuffer(m.rc_constants, CL_TRUE, 0, sizeof(f32), f32.data());
    }
    set_args(m.clear_range, m.rc_near, m.rc_far, cl_uint(n_tiles));
    enqueue_1d(q, m.clear_range, n_tiles);
    set_args(m.range, m.table, cl_uint(m.entries), m.rc_constants, W, H, TW, TH, m.rc_near, m.rc_far);
    enqueue_1d(q, m.range, m.entries);
    // The regions that hold a block (VoxelBlockGrid::region_occupied): at most one per block, in a set of
    // `entries` >= 2 capacity slots.
    q.enqueueFillBuffer(m.rc_regions, cl_uint(0), 0, m.entries * sizeof(cl_uint));
    set_args(m.regions, m.table, cl_uint(m.entries), m.rc_regions, cl_uint(m.entries - 1));
    enqueue_1d(q, m.regions, m.entries);
    q.finish();
    const auto t1 = std::chrono::steady_clock::now();
    m.rc_times.range_ms = std::chrono::duration<double, std::milli>(t1 - t0).count();

    // What every ray shares, as raycast.cpp's RayCaster computes it.
    RaycastParams P{};
    const Eigen::Matrix3f R = T_world_camera.rotation().cast<float>();
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) P.R_wc[3 * i + j] = R(i, j);
    const Eigen::Vector3f o =
        (T_world_camera.translation() / params_.voxel_m).cast<float>() - Eigen::Vector3f::Constant(0.5f);
    for (int i = 0; i < 3; ++i) P.o_vox[i] = o[i];
    P.voxel_m = float(params_.voxel_m);
    P.mu_m = float(params_.truncation_m());
    P.step_fraction = float(options.step_fraction);
    P.min_step_m = float(options.min_step_vox * params_.voxel_m);
    P.refine_tol_m = float(options.refine_tol_vox * params_.voxel_m);
    P.min_depth_m = float(options.min_depth_m);
    P.max_depth_m = float(options.max_depth_m);
    P.min_weight_raw = std::max(1, int(hf_quantise_weight(std::max(0.0f, options.min_weight))));
    P.skip_blocks = options.skip_blocks ? 1 : 0;
    P.region_mask = cl_uint(m.entries - 1);
    P.colour = options.color ? 1 : 0;
    P.K = camera.kernel_intrinsics();
    const cl_uint zero = 0;
    q.enqueueWriteBuffer(m.rc_hits, CL_FALSE, 0, sizeof(zero), &zero);
    const bool has_hints = options.depth_hint != nullptr;
    if (has_hints) q.enqueueWriteBuffer(m.rc_hints, CL_FALSE, 0, n_pixels * sizeof(float), options.depth_hint->data());
    set_args(m.march, m.table, cl_uint(m.entries - 1), m.shift, m.options.max_probe, m.pool, m.flags, m.rc_regions,
             m.rc_near, m.rc_far, TW, m.rc_constants);
    m.march.setArg(11, sizeof(P), &P);
    set_args_from(m.march, 12, m.rc_hints, cl_int(has_hints ? 1 : 0), m.rc_depth, m.rc_vertices, m.rc_normals,
                  m.rc_colour, m.rc_hits);
    // 8 x 8 work-groups: a group's rays are one range tile and read neighbouring voxels.
    q.enqueueNDRangeKernel(m.march, cl::NullRange, cl::NDRange(round_up(size_t(W), 8), round_up(size_t(H), 8)),
                           cl::NDRange(8, 8));
    q.finish();
    const auto t2 = std::chrono::steady_clock::now();
    m.rc_times.march_ms = std::chrono::duration<double, std::milli>(t2 - t1).count();
    cl_uint hits = 0;
    q.enqueueReadBuffer(m.rc_depth, CL_FALSE, 0, n_pixels * sizeof(float), out->depth.data());
    q.enqueueReadBuffer(m.rc_vertices, CL_FALSE, 0, n_pixels * sizeof(hf_float4), out->vertices.data());
    q.enqueueReadBuffer(m.rc_normals, CL_FALSE, 0, n_pixels * sizeof(hf_float4), out->normals.data());
    static_assert(sizeof(Rgb8) == 3, "packed colour");
    if (options.color) q.enqueueReadBuffer(m.rc_colour, CL_FALSE, 0, n_pixels * 3, out->color.data());
    q.enqueueReadBuffer(m.rc_hits, CL_TRUE, 0, sizeof(hits), &hits);
    m.rc_times.read_ms = ms_since(t2);
    out->hit_count = int(hits);
    // The maps stay on the device as the host images' copies (core/device_copy.h): the model pyramid and the
    // reduction on this context bind them instead of uploading the read-back.
    struct Output {
      const void* host;
      size_t bytes;
      const cl::Buffer* buffer;
    };
    for (const Output& o : {Output{out->depth.data(), n_pixels * sizeof(float), &m.rc_depth},
                            Output{out->vertices.data(), n_pixels * sizeof(hf_float4), &m.rc_vertices},
                            Output{out->normals.data(), n_pixels * sizeof(hf_float4), &m.rc_normals}}) {
      out->device_copies.add(o.host, m.ctx->publish(o.host, o.bytes, *o.buffer));
    }
    if (options.shade) {
      // raycast.cpp's pixel write of the shading, on the host from the read-back normals: the same ray
      // direction (PinholeCamera's doubles, then float) and hf_headlight_shade.
      for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
          Rgb8& g = out->shaded(x, y);
          if (out->depth(x, y) <= 0.0f) {
            g = Rgb8{};
            continue;
          }
          const hf_float4 n = out->normals(x, y);
          if (n.w == 0.0f) {
            g = Rgb8{40, 40, 40};
            continue;
          }
          const Eigen::Vector3f d(float((x - camera.cx) / camera.fx), float((y - camera.cy) / camera.fy), 1.0f);
          const float len = d.norm();
          const hf_float4 to_cam = hf_make_float4(-d.x() / len, -d.y() / len, -1.0f / len, 0.0f);
          const auto v = std::uint8_t(255.0f * hf_headlight_shade(n, to_cam) + 0.5f);
          g = Rgb8{v, v, v};
        }
    }
  } catch (const Error&) {
    throw;
  } catch (...) {
    opencl::rethrow_as_hf_error("raycast on " + device_name());
  }
}

}  // namespace hf::fusion
