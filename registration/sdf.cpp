#include "registration/sdf.h"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>

#include <Eigen/Core>

#include "core/error.h"
#include "fusion/flat_block_map.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"
#include "registration/dense_method.h"
#include "registration/gauss_newton.h"
#include "registration/kernels/sdf_kernel.h"

namespace hf {
namespace {

// The kernel's parameters (registration/kernels/sdf_kernel.h, all a device sees: DenseKernel::params_bytes) and,
// for the cpu rows, the host grid they read through VolumeSampler.
struct SdfParams {
  hf_sdf_params k{};
  const fusion::VoxelBlockGrid* grid = nullptr;
  float min_voxel_weight = 0.0f;  // the sampler's form of k.min_weight_raw
};
static_assert(offsetof(SdfParams, k) == 0, "the kernel's parameters lead the host struct");

// One pixel's row over the host grid: the kernel header's steps around the sampler's cached gather.
int sdf_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const hf_sdf_params& p,
              fusion::VolumeSampler& sampler, hf_reg_row* row) {
  hf_float4 v;
  int cell[3];
  float frac[3];
  if (!hf_sdf_locate(x, y, maps, K, T, p, &v, cell, frac)) return 0;
  const float* raw = sampler.cell_corners(cell[0], cell[1], cell[2]);
  if (raw == nullptr) return 0;
  float weight = 0.0f;
  if (p.confidence_weight_raw > 0.0f) {
    int least = 1 << 30;
    for (int c = 0; c < 8; ++c) {
      const fusion::Voxel* vx = sampler.voxel(cell[0] + (c & 1), cell[1] + ((c >> 1) & 1), cell[2] + (c >> 2));
      least = std::min(least, vx != nullptr ? int(vx->weight) : 0);
    }
    weight = float(least);
  }
  return hf_sdf_row(raw, frac, v, p, weight, row);
}

// The cpu backend's loop over rows [y0, y1): one sampler (block cache) per call, the calls run concurrently.
void sdf_rows(const ResidualProblem& problem, int y0, int y1, double* sums) {
  const SdfParams& p = *static_cast<const SdfParams*>(problem.params);
  if (p.grid == nullptr) return;
  fusion::VolumeSampler sampler(*p.grid, p.min_voxel_weight, false);
  const hf_reg_maps maps = problem.kernel_maps();
  const int step = problem.pixel_step > 1 ? problem.pixel_step : 1;
  for (int y = y0; y < y1; ++y) {
    if (y % step != 0) continue;
    for (int x = 0; x < problem.width(); x += step) {
      hf_reg_row row;
      if (sdf_pixel(x, y, &maps, problem.camera, problem.T_ref_cur, p.k, sampler, &row)) hf_reg_accumulate(&row, sums);
    }
  }
}

int sdf_one_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const void* params,
                  hf_reg_row* rows) {
  const SdfParams& p = *static_cast<const SdfParams*>(params);
  if (p.grid == nullptr) return 0;
  fusion::VolumeSampler sampler(*p.grid, p.min_voxel_weight, false);
  return sdf_pixel(x, y, maps, K, T, p.k, sampler, rows);
}

DenseKernel make_sdf_kernel() {
  DenseKernel k;
  k.name = "sdf";
  k.inputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES) | HF_REG_IN_BIT(HF_SDF_IN_TABLE) | HF_REG_IN_BIT(HF_SDF_IN_POOL);
  k.max_rows = 1;
  k.params_bytes = sizeof(hf_sdf_params);
  k.pixel = &sdf_one_pixel;
  k.rows = &sdf_rows;
  return k;
}
const DenseKernel kSdfKernel = make_sdf_kernel();

// The map in the kernel's flat layout (fusion/flat_block_map.h), built only when a device backend asks for it
// (KernelBuffer): one copy of every block, once per map version (a set_volume or a pairwise fusion), whatever
// the number of levels and iterations that read it. The table and the pool are two slots, two views of one copy.
// The table has the grid's own hash geometry (bit_ceil(max(16, 2 capacity_blocks)) entries), which is the
// device map's (fusion/opencl/device_voxel_grid.h): where the map lives on the device and its table and pool are
// published as the grid's copy, the backend binds those (resident_key) and no copy is built or uploaded.
class FlatMapCache {
 public:
  void set(const fusion::VoxelBlockGrid* grid) {
    grid_ = grid;
    entries_ = fusion::flat_table_entries(std::max(grid->block_count(), grid->params().capacity_blocks));
    version_ = new_kernel_buffer_version();
  }
  const fusion::VoxelBlockGrid* grid() const { return grid_; }
  std::uint64_t version() const { return version_; }
  // The table's size, known before the copy is built (the kernel's parameters need it per level).
  size_t entries() const { return entries_; }
  const fusion::FlatBlockMap& flat() const {
    if (built_ != version_) {
      flat_ = fusion::flatten(*grid_, entries_);
      built_ = version_;
    }
    return flat_;
  }

  class Part final : public KernelBuffer {
   public:
    Part(const FlatMapCache& cache, bool table) : cache_(cache), table_(table) {}
    std::uint64_t version() const override { return cache_.version(); }
    std::pair<const void*, std::size_t> contents() const override {
      const fusion::FlatBlockMap& f = cache_.flat();
      if (table_) return {f.table.data(), f.table.size() * sizeof(hf_block_entry)};
      return {f.pool.data(), f.pool.size() * sizeof(fusion::Voxel)};
    }
    std::pair<const void*, std::size_t> resident_key() const override {
      const fusion::VoxelBlockGrid* grid = cache_.grid();
      if (grid == nullptr) return {nullptr, 0};
      return {grid, table_ ? cache_.entries() * sizeof(hf_block_entry)
                           : grid->params().capacity_blocks * sizeof(fusion::VoxelBlock)};
    }

   private:
    const FlatMapCache& cache_;
    bool table_;
  };

 private:
  const fusion::VoxelBlockGrid* grid_ = nullptr;
  size_t entries_ = 16;
  std::uint64_t version_ = 0;
  mutable std::uint64_t built_ = ~std::uint64_t(0);
  mutable fusion::FlatBlockMap flat_;
};

class SdfMethod final : public DenseMethod {
 public:
  explicit SdfMethod(const SdfOptions& options)
      : options_(options), table_(flat_, true), pool_(flat_, false) {
    params_.k.max_abs_sdf = options.max_abs_sdf;
    params_.k.depth_noise_ref_m = options.depth_noise_ref_m;
    params_.k.confidence_weight_raw = options.confidence_weight * HF_WEIGHT_SCALE;
    params_.min_voxel_weight = options.min_voxel_weight;
    // VolumeSampler's rule: weight 0 (never observed) is always unobserved.
    params_.k.min_weight_raw = std::max(1, int(hf_quantise_weight(std::max(0.0f, options.min_voxel_weight))));
    params_.k.robust =
        robust_params(options.robust_sdf, options.huber_sdf_m, options.t_sigma_sdf_m, options.t_dof_sdf);
  }
  const DenseKernel& kernel() const override { return kSdfKernel; }
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices, options_.finest_level_step));
  }
  bool aligns_to_volume() const override { return true; }
  // The map changes between calls (the pipeline integrates a frame): a new version of the device copy each time.
  void set_volume(const fusion::VoxelBlockGrid* grid, const SE3& T_world_ref) override {
    volume_ = grid;
    T_world_ref_ = T_world_ref;
    if (grid != nullptr) flat_.set(grid);
  }
  bool reads_reference() const override { return volume_ == nullptr; }

  int pixel_step() const override { return level_ == 0 ? options_.finest_level_step : 1; }

  void begin_level(int level, const FramePyramidLevel&, const FramePyramidLevel& reference,
                   ResidualProblem& problem) override {
    level_ = level;
    const fusion::VoxelBlockGrid* grid = volume_;
    SE3 T_world_ref = T_world_ref_;
    if (grid == nullptr) {  // pairwise: the reference level fused into a volume of its own, at the identity
      fuse_reference(reference);
      grid = own_.get();
      T_world_ref = SE3();
      flat_.set(grid);
    }
    params_.grid = grid;
    params_.k.T_world_ref = to_transform12(T_world_ref);
    params_.k.inv_voxel_m = float(1.0 / grid->params().voxel_m);
    params_.k.mu_m = float(grid->params().truncation_m());
    params_.k.step = pixel_step();
    // The flat copy's table (fusion/flat_block_map.h), sized before the copy is built; the look-up bound is the
    // table itself (a look-up stops at an empty entry, and at least half of them are).
    const size_t entries = flat_.entries();
    params_.k.table_mask = std::uint32_t(entries - 1);
    params_.k.table_shift = 64 - std::countr_zero(entries);
    params_.k.table_max_probe = int(entries);
    problem.set_buffer(HF_SDF_IN_TABLE, &table_);
    problem.set_buffer(HF_SDF_IN_POOL, &pool_);
  }

 private:
  // One volume kept across calls and cleared (its pool chunks stay allocated): pairwise use registers every
  // keyframe pair this way. 2^16 blocks hold one frame's band at any tracking resolution (a 640x480 frame of a
  // room touches ~10^4); more is a CapacityError, which the driver reports as a failed registration.
  void fuse_reference(const FramePyramidLevel& reference) {
    if (own_ == nullptr) {
      fusion::VolumeParams vp;
      vp.voxel_m = options_.own_voxel_m;
      vp.truncation_vox = options_.own_truncation_vox;
      vp.capacity_blocks = 1 << 16;
      own_ = std::make_unique<fusion::VoxelBlockGrid>(vp);
    } else {
      own_->clear();
    }
    fusion::integrate(*own_, depth_of(reference.vertices), ColorImage(), reference.camera, SE3());
  }

  SdfOptions options_;
  SdfParams params_;
  FlatMapCache flat_;
  FlatMapCache::Part table_, pool_;
  int level_ = 0;
  const fusion::VoxelBlockGrid* volume_ = nullptr;
  SE3 T_world_ref_;
  std::unique_ptr<fusion::VoxelBlockGrid> own_;
};

// 20 / 10 / 10 iterations (finest first), not KinectFusion's 10 / 5 / 4: the field's gradient is that of one
// trilinear cell, so a step lands where the linearisation of that cell puts it and Gauss-Newton needs more of them
// than projective ICP. Chosen on fr1/rpy frames 0-149: ATE 8.96 cm at 10 / 5 / 4, 6.68 at 20 / 10 / 10, 6.78 at
// 40 / 20 / 20 (bench/results/sdf_tracking.md).
RegistrationOptions sdf_defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {20, 10, 10};
  return RegistrationOptions(driver, std::make_unique<SdfOptions>());
}

std::unique_ptr<Registration> make_sdf(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  return std::make_unique<GaussNewtonRegistration>(
      "sdf", std::make_unique<SdfMethod>(options.method_as<SdfOptions>()), options, std::move(backend));
}

}  // namespace

void SdfOptions::visit(OptionVisitor& v) {
  v("max_abs_sdf", max_abs_sdf);
  v("finest_level_step", finest_level_step);
  v("min_voxel_weight", min_voxel_weight);
  v("robust_sdf", robust_sdf);
  v("huber_sdf_m", huber_sdf_m);
  v("t_sigma_sdf_m", t_sigma_sdf_m);
  v("t_dof_sdf", t_dof_sdf);
  v("depth_noise_ref_m", depth_noise_ref_m);
  v("confidence_weight", confidence_weight);
  v("own_voxel_m", own_voxel_m);
  v("own_truncation_vox", own_truncation_vox);
}

void SdfOptions::validate() const {
  require_option(max_abs_sdf > 0.0f && max_abs_sdf <= 1.0f, "max_abs_sdf must be in (0, 1]");
  require_option(finest_level_step >= 1 && finest_level_step <= 16, "finest_level_step must be in [1, 16]");
  require_option(std::isfinite(min_voxel_weight) && min_voxel_weight >= 0.0f, "min_voxel_weight must be >= 0");
  require_option(finite_positive(huber_sdf_m), "huber_sdf_m must be finite and > 0");
  require_option(finite_positive(t_sigma_sdf_m), "t_sigma_sdf_m must be finite and > 0");
  require_option(finite_positive(t_dof_sdf), "t_dof_sdf must be finite and > 0");
  require_option(std::isfinite(depth_noise_ref_m) && depth_noise_ref_m >= 0.0f,
                 "depth_noise_ref_m must be finite and >= 0");
  require_option(std::isfinite(confidence_weight) && confidence_weight >= 0.0f && confidence_weight <= 4096.0f,
                 "confidence_weight must be in [0, 4096]");
  require_option(own_voxel_m > 0.0 && own_voxel_m <= 1.0, "own_voxel_m must be in (0, 1] metres");
  require_option(own_truncation_vox >= 1.0 && own_truncation_vox <= 64.0, "own_truncation_vox must be in [1, 64]");
}

RegistrationMethod sdf_registration_method() { return {"sdf", sdf_defaults, make_sdf}; }

}  // namespace hf
