// A per-pixel least-squares method on the Gauss-Newton driver (registration/gauss_newton.h): what a method
// supplies, and the helpers that turn its kernel header into a DenseKernel.
//
//   // registration/kernels/mine_kernel.h: hf_mine_params and
//   //   int hf_mine_pixel(int x, int y, const hf_reg_maps*, hf_intrinsics, hf_transform12, hf_mine_params,
//   //                     hf_reg_row*), ending with HF_REG_OPENCL_KERNEL(mine, hf_mine_pixel, hf_mine_params)
//   const DenseKernel kMine = make_dense_kernel<hf_mine_params, hf_mine_pixel>("mine", inputs, max_rows);
//   class MineMethod : public DenseMethod { ... };  // its parameters per level, from its own options
//
// The driver owns the pyramid loop, convergence, IRLS bookkeeping, the degeneracy-aware solve and the outcome
// checks; the method owns its residual, its parameters and any per-iteration scale estimate (DVO's sigma).
// registration/README.md says how to add one.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/se3.h"
#include "registration/frame_pyramid.h"
#include "registration/reduction.h"

namespace hf {

namespace fusion {
class VoxelBlockGrid;  // fusion/voxel_block_grid.h
}

enum class RobustKernel;  // registration/registration.h

// The kernel-side robust weight (HF_ROBUST_*) of a term: scale = huber_k for Huber, sigma for Student-t.
hf_reg_robust robust_params(RobustKernel kernel, float huber_k, float t_sigma, float t_dof);

// The driver's view of a method, one object per Registration (not shared between threads).
class DenseMethod {
 public:
  virtual ~DenseMethod() = default;
  virtual const DenseKernel& kernel() const = 0;
  // Called once per pyramid level before its iterations (level 0 finest, levels coarse to fine). The method sets
  // up the parameters params() returns for that level; it may fill its own map slots (HF_REG_IN_METHOD0..) of
  // `problem` from the two levels (it owns that storage).
  virtual void begin_level(int level, const FramePyramidLevel& current, const FramePyramidLevel& reference,
                           ResidualProblem& problem) = 0;
  virtual const void* params() const = 0;
  // Only pixels with x and y multiples of this give rows at the level begun last (ResidualProblem::pixel_step).
  virtual int pixel_step() const { return 1; }
  // After each iteration's reduction (with a solvable system): e.g. re-estimate a robust scale for the next one.
  virtual void end_iteration(const NormalEquations& ne) { (void)ne; }
  // The rows the finest level could give at most (for RegistrationResult::inlier_ratio).
  virtual double rows_possible(const FramePyramidLevel& current) const = 0;

  // A method whose rows are several terms weighed per direction (combined: "icp", "photometric") names them here
  // (RegistrationResult::terms). The driver then reduces each term's problem on its own instead of kernel()'s,
  // and solves the system combine_terms() makes of them. Empty (the default): one reduction of kernel().
  virtual std::vector<std::string> term_names() const { return {}; }
  // Term t's problem at the level begun last: `level`'s maps and version with the term's kernel, params and step.
  virtual ResidualProblem term_problem(int t, const ResidualProblem& level) const {
    (void)t;
    return level;
  }
  // The system the step is solved from, from each term's normal equations (term_names() order); unit_scale is
  // the driver's balanced units S (balanced_units(), registration/gauss_newton.h).
  virtual NormalEquations combine_terms(const std::vector<NormalEquations>& terms, const Vector6d& unit_scale) const {
    (void)unit_scale;
    return terms.empty() ? NormalEquations{} : terms.front();
  }
  // Once per level, at its first iteration (before combine_terms), with that iteration's terms: a method may
  // reduce term t again at the pose moved by xi (tangent vector, applied on the left of the current estimate),
  // e.g. to check a term's information against the curvature its cost shows when the correspondences are
  // re-found (combined). Whatever it learns applies to combine_terms() for the rest of the level.
  using TermProbe = std::function<NormalEquations(int term, const Vector6d& xi)>;
  virtual void probe_terms(const std::vector<NormalEquations>& terms, const Vector6d& unit_scale,
                           const TermProbe& reduce_at) {
    (void)terms;
    (void)unit_scale;
    (void)reduce_at;
  }

  // A method whose rows read a map rather than the reference pyramid (sdf): Registration::aligns_to_volume and
  // set_volume, passed through by the driver. While reads_reference() is false the driver asks nothing of the
  // reference pyramid (begin_level gets the current level in its place) and does not verify a large motion by the
  // reverse problem (a frame cannot be aligned onto a map the other way round).
  virtual bool aligns_to_volume() const { return false; }
  virtual void set_volume(const fusion::VoxelBlockGrid* grid, const SE3& T_world_ref) {
    (void)grid;
    (void)T_world_ref;
  }
  virtual bool reads_reference() const { return true; }
};

// Valid vertices on the pixel grid x, y = 0, step, 2 step, ...
long count_valid_pixels(const VertexMap& vertices, int step = 1);

namespace detail {

// The C++ loop of a kernel: every pixel of rows [y0, y1) on the problem's pixel_step grid, its rows accumulated
// in pixel order (hf_reg_accumulate). Pixel is the kernel header's function, inlined here.
template <class Params, int (*Pixel)(int, int, const hf_reg_maps*, hf_intrinsics, hf_transform12, Params,
                                     hf_reg_row*)>
void dense_rows(const ResidualProblem& p, int y0, int y1, double* sums) {
  const hf_reg_maps maps = p.kernel_maps();
  const Params params = *static_cast<const Params*>(p.params);
  const int step = p.pixel_step > 1 ? p.pixel_step : 1;
  for (int y = y0; y < y1; ++y) {
    if (y % step != 0) continue;
    for (int x = 0; x < p.width(); x += step) {
      hf_reg_row rows[HF_REG_MAX_ROWS];
      const int n = Pixel(x, y, &maps, p.camera, p.T_ref_cur, params, rows);
      for (int k = 0; k < n; ++k) hf_reg_accumulate(&rows[k], sums);
    }
  }
}

template <class Params, int (*Pixel)(int, int, const hf_reg_maps*, hf_intrinsics, hf_transform12, Params,
                                     hf_reg_row*)>
int dense_pixel(int x, int y, const hf_reg_maps* maps, hf_intrinsics K, hf_transform12 T, const void* params,
                hf_reg_row* rows) {
  return Pixel(x, y, maps, K, T, *static_cast<const Params*>(params), rows);
}

}  // namespace detail

// The descriptor of a kernel header's pixel function. rows_avx2: the method's eight-lane spelling, or null (the
// cpu backend then runs the scalar loop for it). opencl_source: see DenseKernel.
template <class Params, int (*Pixel)(int, int, const hf_reg_maps*, hf_intrinsics, hf_transform12, Params,
                                     hf_reg_row*)>
constexpr DenseKernel make_dense_kernel(const char* name, unsigned inputs, int max_rows,
                                        RowsFunction rows_avx2 = nullptr, const char* opencl_source = "") {
  DenseKernel k;
  k.name = name;
  k.inputs = inputs;
  k.max_rows = max_rows;
  k.params_bytes = sizeof(Params);
  k.pixel = &detail::dense_pixel<Params, Pixel>;
  k.rows = &detail::dense_rows<Params, Pixel>;
  k.rows_avx2 = rows_avx2;
  k.opencl_source = opencl_source;
  return k;
}

}  // namespace hf
