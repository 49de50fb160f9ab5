// The voxel-block map on an OpenCL device, integrate() and the tracking raycast there (issue 20).
//
//   auto ctx = hf::opencl::Context::shared();           // core/opencl/opencl_context.h: device choice
//   hf::fusion::DeviceVoxelGrid map(volume, ctx);        // volume: VolumeParams (validated)
//   map.integrate(depth, colour, camera, T_world_camera, params);  // as fusion::integrate, on the device
//   map.raycast(camera, T_world_camera, raycast_options, &model);  // as fusion::raycast
//   VoxelBlockGrid grid(volume);  map.read_into(grid);   // meshing, streaming, save/load on the host
//
// Layout, VoxelBlockGrid's (fusion/block_hash_table.h, fusion/kernels/voxel.h): a table of
// bit_ceil(max(16, 2 capacity_blocks)) 16-byte entries {x, y, z, value = pool slot + 1, 0 empty}, the home entry
// BlockHashTable's Fibonacci mix of the coordinates, linear probing bounded by DeviceGridOptions::max_probe; a pool
// of capacity_blocks blocks of 512 8-byte hf_voxels (x fastest), allocated on the device up front.
//
// integrate() is fusion::integrate's two phases as kernels (fusion/opencl/integrate.cl): the CPU's band and
// block walk per pixel (same arithmetic and neighbour skip, so the same blocks), a parallel look-up, creation of
// the missing blocks by one work-item (no 64-bit atomics needed: OpenCL 1.2 has 32-bit ones only), then the shared
// per-voxel kernel of fusion/kernels/integrate_kernels.h, projective or point-to-plane, and each updated block's
// surface-free flag (VoxelBlockGrid::surface_free, for the raycast's block skip). On a device with
// cl_khr_fp64 and correctly rounded division (PoCL) the voxels equal the CPU's bit for bit
// (tests/fusion/opencl); without fp64 the band geometry is float and edge blocks may differ.
//
// Errors: hf::Error for a frame whose size does not match the camera, and for OpenCL failures ("integrate on
// DEVICE: clX: CL_NAME (code)"); CapacityError (fusion/voxel_block_grid.h) when the pool is full or a block's
// probe run would exceed max_probe, naming the block: the frame is then partly allocated and no voxel updated,
// as on the CPU (a block that found no slot stays missing). DeviceMemoryError from the constructor when the pool
// does not fit the device's largest allocation or its memory. A NaN, zero or out-of-range depth pixel allocates
// nothing; an empty frame changes nothing.
//
// Not (yet) on the device: releasing blocks (garbage collection, streaming: the pool only grows until clear()),
// deintegration (the frame pyramid: registration/opencl/device_pyramid.h). Thread-safety:
// one call at a time per map (the context's queue is shared: other users of the context must serialise their own
// command sequences, as the registration backend does).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "core/camera.h"
#include "core/device_copy.h"
#include "core/error.h"
#include "core/image.h"
#include "core/se3.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"

namespace hf::opencl {
class Context;
}

namespace hf::fusion {

// The device cannot hold the map (pool larger than its largest allocation or its global memory).
class DeviceMemoryError : public Error {
 public:
  using Error::Error;
};

struct DeviceGridOptions {
  // Longest probe run of a block's entry from its home; a longer one is a CapacityError. 64 entries at load
  // <= 0.5 is far beyond the runs linear probing makes there (mean ~1.5).
  int max_probe = 64;
};

class DeviceVoxelGrid {
 public:
  // context null = hf::opencl::Context::shared(). Throws hf::Error (no platform, bad params), DeviceMemoryError.
  explicit DeviceVoxelGrid(const VolumeParams& params, std::shared_ptr<opencl::Context> context = nullptr,
                           const DeviceGridOptions& options = {});
  ~DeviceVoxelGrid();
  DeviceVoxelGrid(const DeviceVoxelGrid&) = delete;
  DeviceVoxelGrid& operator=(const DeviceVoxelGrid&) = delete;

  const VolumeParams& params() const { return params_; }
  // "platform / device" of the device the map lives on.
  std::string device_name() const;

  // fusion::integrate (fusion/integrate.h) on the device, with the same inputs, stats (blocks_streamed_in 0) and
  // errors (see above). allocate_ms / update_ms are wall time on the host, each phase up to its completion.
  IntegrateStats integrate(const DepthImage& depth, const ColorImage& colour, const PinholeCamera& camera,
                           const SE3& T_world_camera, const IntegrateParams& params = {});

  size_t block_count() const;
  // Copies every device block into `grid` (same voxel_m, truncation and max_weight, else hf::Error), creating the
  // blocks it lacks and overwriting the ones it has; each copied block's surface_free flag is set from its voxels.
  // Blocks of `grid` the device does not hold are left alone. Throws CapacityError when `grid` runs out of room.
  // Returns the number of blocks copied.
  size_t read_into(VoxelBlockGrid& grid) const;
  // The same for the blocks the last integrate() updated (its visible set): what a host copy of the map needs to
  // follow the device after one frame.
  size_t read_last_frame_into(VoxelBlockGrid& grid) const;
  // Replaces the device map by the host grid's blocks (clear(), then every block of `grid`): for a host that
  // changed its copy (deintegration, re-fusion, loading a volume). Same parameter check as read_into; CapacityError
  // when the blocks do not fit the pool or the probe bound.
  void load(const VoxelBlockGrid& grid);
  void clear();
  // Publishes the map's table and pool (the flat layout of fusion/kernels/block_hash.h, the table with
  // `mirror`'s hash geometry) on the context as the copy of `mirror` (core/device_copy.h; keys (&mirror, table
  // bytes) and (&mirror, pool bytes), what sdf's KernelBuffer::resident_key asks for), so a kernel that reads the
  // host grid in the flat layout reads the device map in place. The caller vouches that `mirror` holds the same
  // blocks (the host copy it keeps with read_last_frame_into / load) and keeps the returned copies only while both
  // stay unchanged: integrate(), load() and clear() throw hf::Error while a holder keeps them. Same parameter
  // check as read_into.
  DeviceCopies publish_map(const VoxelBlockGrid& mirror) const;

  // The tracking raycast of fusion/raycast.h on the device map (fusion/opencl/raycast.cl: the range image, the
  // march with cheap steps, jumps over missing blocks and empty 4^3-block regions, one-step crossings of
  // surface-free blocks with options.skip_blocks (the flags integrate() keeps on the device and load() copies), the
  // search around options.depth_hint first, the refined crossing, the normal; the samples from the shared kernel
  // headers): depth, vertices and normals in the camera frame into *out (images resized as raycast() does), the
  // trilinear colour with options.color (else black), the head-light shading with options.shade (from the
  // normals, on the host). It samples where raycast() does, so the two agree but for float rounding of the ray set-up
  // (tests/fusion/opencl). The depth, vertex and normal maps stay on the device as the read-back images' copies
  // (out->device_copies, core/device_copy.h): the model pyramid and the reductions on this context bind them; a
  // later raycast never writes a copy a holder still keeps. Throws hf::Error as raycast() does for bad options, a
  // bad camera or pose, and for OpenCL failures. last_raycast_times(): the range image (with the region set), the
  // march, the read-back.
  void raycast(const PinholeCamera& camera, const SE3& T_world_camera, const RaycastOptions& options,
               RaycastResult* out) const;
  struct RaycastTimes {
    double range_ms = 0.0, march_ms = 0.0, read_ms = 0.0;
  };
  RaycastTimes last_raycast_times() const;

 private:
  void check_host_grid(const VoxelBlockGrid& grid) const;
  struct Impl;
  VolumeParams params_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace hf::fusion
