#include "registration/sdf.h"

#include <cmath>
#include <memory>

#include <Eigen/Core>

#include "core/error.h"
#include "fusion/integrate.h"
#include "fusion/raycast.h"
#include "fusion/voxel_block_grid.h"
#include "registration/cpu_backend.h"
#include "registration/dense_method.h"
#include "registration/gauss_newton.h"

namespace hf {
namespace {

// What a row needs besides the current vertices: the map (host memory), where the reference camera sits in it,
// the gates and the robust weight.
struct SdfParams {
  const fusion::VoxelBlockGrid* grid = nullptr;
  Eigen::Matrix3f R_world_ref = Eigen::Matrix3f::Identity();
  Eigen::Vector3f t_world_ref = Eigen::Vector3f::Zero();
  float inv_voxel_m = 100.0f;
  float mu_m = 0.04f;
  float max_abs_sdf = 0.9f;
  float min_voxel_weight = 0.0f;
  hf_reg_robust robust{};
};

// The trilinear normalised SDF at p_vox (voxel centres at integers) and its analytic gradient in the same cell
// (normalised sdf per voxel); false when one of the eight voxels is unobserved or p_vox is not finite.
bool sdf_and_gradient(fusion::VolumeSampler& sampler, const Eigen::Vector3f& p_vox, float* d, Eigen::Vector3f* g) {
  if (!(std::fabs(p_vox.x()) < 1e9f && std::fabs(p_vox.y()) < 1e9f && std::fabs(p_vox.z()) < 1e9f)) return false;
  const Eigen::Vector3f fl = p_vox.array().floor();
  const int i = int(fl.x()), j = int(fl.y()), k = int(fl.z());
  const float a = p_vox.x() - fl.x(), b = p_vox.y() - fl.y(), c = p_vox.z() - fl.z();
  const float* raw = sampler.cell_corners(i, j, k);
  if (raw == nullptr) return false;
  float f[8];
  for (int n = 0; n < 8; ++n) f[n] = raw[n] * (1.0f / HF_SDF_SCALE);
  // Along x, then y, then z; the gradient is the derivative of the same polynomial.
  const float x00 = f[0] + a * (f[1] - f[0]), x10 = f[2] + a * (f[3] - f[2]);
  const float x01 = f[4] + a * (f[5] - f[4]), x11 = f[6] + a * (f[7] - f[6]);
  const float y0 = x00 + b * (x10 - x00), y1 = x01 + b * (x11 - x01);
  *d = y0 + c * (y1 - y0);
  const float dx0 = (f[1] - f[0]) + b * ((f[3] - f[2]) - (f[1] - f[0]));
  const float dx1 = (f[5] - f[4]) + b * ((f[7] - f[6]) - (f[5] - f[4]));
  *g = Eigen::Vector3f(dx0 + c * (dx1 - dx0), (x10 - x00) + c * ((x11 - x01) - (x10 - x00)), y1 - y0);
  return true;
}

// One pixel's row: r = D(T_world_ref T_ref_cur v_cur) in metres, dr/dv = R_world_ref^T grad D.
int sdf_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const SdfParams& p,
              fusion::VolumeSampler& sampler, hf_reg_row* row) {
  const hf_float4 vc = hf_reg_map4(maps, HF_REG_IN_CUR_VERTICES)[y * K.width + x];
  if (!hf_is_valid4(vc)) return 0;
  const hf_float4 v = hf_reg_transform_point(T, vc);
  const Eigen::Vector3f q = p.R_world_ref * Eigen::Vector3f(v.x, v.y, v.z) + p.t_world_ref;
  float s = 0.0f;
  Eigen::Vector3f g;
  if (!sdf_and_gradient(sampler, q * p.inv_voxel_m - Eigen::Vector3f::Constant(0.5f), &s, &g)) return 0;
  if (!(std::fabs(s) < p.max_abs_sdf)) return 0;
  const float r = s * p.mu_m;
  const Eigen::Vector3f a = p.R_world_ref.transpose() * (g * (p.mu_m * p.inv_voxel_m));
  if (!a.allFinite()) return 0;
  hf_reg_set_row(v, hf_make_float4(a.x(), a.y(), a.z(), 0.0f), r, hf_reg_term_weight(p.robust, r), row);
  return 1;
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
      if (sdf_pixel(x, y, &maps, problem.camera, problem.T_ref_cur, p, sampler, &row)) hf_reg_accumulate(&row, sums);
    }
  }
}

int sdf_one_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const void* params,
                  hf_reg_row* rows) {
  const SdfParams& p = *static_cast<const SdfParams*>(params);
  if (p.grid == nullptr) return 0;
  fusion::VolumeSampler sampler(*p.grid, p.min_voxel_weight, false);
  return sdf_pixel(x, y, maps, K, T, p, sampler, rows);
}

DenseKernel make_sdf_kernel() {
  DenseKernel k;
  k.name = "sdf";
  k.inputs = HF_REG_IN_BIT(HF_REG_IN_CUR_VERTICES);
  k.max_rows = 1;
  k.params_bytes = sizeof(SdfParams);
  k.pixel = &sdf_one_pixel;
  k.rows = &sdf_rows;
  k.host_only = true;
  return k;
}
const DenseKernel kKernel = make_sdf_kernel();

class SdfMethod final : public DenseMethod {
 public:
  explicit SdfMethod(const SdfOptions& options) : options_(options) {
    params_.max_abs_sdf = options.max_abs_sdf;
    params_.min_voxel_weight = options.min_voxel_weight;
    params_.robust = robust_params(options.robust_sdf, options.huber_sdf_m, options.t_sigma_sdf_m, options.t_dof_sdf);
  }
  const DenseKernel& kernel() const override { return kKernel; }
  const void* params() const override { return &params_; }
  double rows_possible(const FramePyramidLevel& current) const override {
    return double(count_valid_pixels(current.vertices, options_.finest_level_step));
  }
  bool aligns_to_volume() const override { return true; }
  void set_volume(const fusion::VoxelBlockGrid* grid, const SE3& T_world_ref) override {
    volume_ = grid;
    T_world_ref_ = T_world_ref;
  }
  bool reads_reference() const override { return volume_ == nullptr; }

  int pixel_step() const override { return level_ == 0 ? options_.finest_level_step : 1; }

  void begin_level(int level, const FramePyramidLevel&, const FramePyramidLevel& reference,
                   ResidualProblem&) override {
    level_ = level;
    const fusion::VoxelBlockGrid* grid = volume_;
    SE3 T_world_ref = T_world_ref_;
    if (grid == nullptr) {  // pairwise: the reference level fused into a volume of its own, at the identity
      fuse_reference(reference);
      grid = own_.get();
      T_world_ref = SE3();
    }
    params_.grid = grid;
    params_.R_world_ref = T_world_ref.rotation().cast<float>();
    params_.t_world_ref = T_world_ref.translation().cast<float>();
    params_.inv_voxel_m = float(1.0 / grid->params().voxel_m);
    params_.mu_m = float(grid->params().truncation_m());
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
  int level_ = 0;
  const fusion::VoxelBlockGrid* volume_ = nullptr;
  SE3 T_world_ref_;
  std::unique_ptr<fusion::VoxelBlockGrid> own_;
};

// 20 / 10 / 10 iterations (finest first), not KinectFusion's 10 / 5 / 4: the field's gradient is that of one
// trilinear cell, so a step lands where the linearisation of that cell puts it and Gauss-Newton needs more of them
// than projective ICP. Chosen on fr1/rpy frames 0-149: ATE 8.96 cm at 10 / 5 / 4, 6.68 at 20 / 10 / 10, 6.78 at
// 40 / 20 / 20 (bench/results/sdf_tracking.md).
RegistrationOptions defaults() {
  GaussNewtonOptions driver;
  driver.iterations = {20, 10, 10};
  return RegistrationOptions(driver, std::make_unique<SdfOptions>());
}

std::unique_ptr<Registration> make(const RegistrationOptions& options, std::unique_ptr<ReductionBackend> backend) {
  // The rows read the map in host memory (DenseKernel::host_only): the cpu backend, whichever was asked for.
  if (backend != nullptr && backend->name() != "cpu") backend = std::make_unique<CpuReductionBackend>();
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
  require_option(own_voxel_m > 0.0 && own_voxel_m <= 1.0, "own_voxel_m must be in (0, 1] metres");
  require_option(own_truncation_vox >= 1.0 && own_truncation_vox <= 64.0, "own_truncation_vox must be in [1, 64]");
}

RegistrationMethod sdf_registration_method() { return {"sdf", defaults, make}; }

}  // namespace hf
