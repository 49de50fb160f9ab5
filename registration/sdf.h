// "sdf": direct volume tracking (Bylow et al. 2013, "Real-Time Camera Tracking and 3D Reconstruction Using Signed
// Distance Functions"; Canelhas et al. 2013, "SDF Tracker"; report section 3.5). The current frame's points are
// aligned to the voxel-hashed TSDF itself instead of to a raycast of it:
//
//   r(p) = D(T_world_ref T_ref_cur p)          D: the trilinear TSDF in metres (normalised sdf * mu)
//   dr/dv = R_world_ref^T grad D               v = T_ref_cur p, grad D: the analytic gradient of the trilinear cell
//
// on the shared Gauss-Newton driver (pyramid of the current frame, robust weights, the balanced degeneracy-aware
// solve, the outcome rules). A point gives a row only where its eight voxels are observed and |sdf| < max_abs_sdf
// (in the truncated band the field is flat: no gradient, and its value is a bound, not a distance).
//
// Where the map comes from: Registration::set_volume (the SLAM pipeline hands over its map and the last pose, and
// then skips the tracking raycast: Registration::aligns_to_volume). Without one (a pairwise use, the registry's
// tests), the method fuses the reference level it is given into a volume of its own (voxel_m, identity pose) and
// aligns to that, so it is a drop-in pairwise method too.
//
// Backends: the rows are registration/kernels/sdf_kernel.h on every backend. The cpu rows gather each trilinear cell
// from the host grid (VolumeSampler's cache); a device backend (OpenCL) reads the map in the flat layout of the
// device voxel-block hash (fusion/kernels/block_hash.h), copied from the host grid once per map version when the
// backend first asks (KernelBuffer, registration/reduction.h: one copy of every block per registration call in the
// pipeline, per pyramid level pairwise). The two agree to the order of the double sums (tests/registration:
// test_opencl_backend, test_accuracy).
#pragma once

#include "registration/registration.h"

namespace hf {

// The measurements behind the defaults: bench/results/sdf_tracking.md (chosen on fr1/rpy frames 0-149, reported
// on 150-269, 0-269, fr1/desk and 7-Scenes).
struct SdfOptions : MethodOptionsBase<SdfOptions> {
  // Rows only where |normalised sdf| is below this: 1 is the truncation band's edge, where the field goes flat.
  float max_abs_sdf = 0.9f;
  // Rows from every finest_level_step-th pixel in x and y at the finest level (coarser levels: every pixel). 2,
  // chosen on fr1/rpy frames 0-149 at 20 / 10 / 10 iterations: ATE 6.68 / 6.57 / 6.52 cm and track 84 / 28 / 31
  // ms per frame for steps 1 / 2 / 3 (loaded machine, same run): the quarter of the rows costs nothing measurable.
  int finest_level_step = 2;
  // Voxels observed fewer times count as unobserved (TSDF weight units; 0: any observation).
  float min_voxel_weight = 0.0f;
  // IRLS weights of the distance (metres): Huber with k, or Student-t with a fixed sigma.
  RobustKernel robust_sdf = RobustKernel::huber;
  float huber_sdf_m = 0.01f;
  float t_sigma_sdf_m = 0.01f;
  float t_dof_sdf = 5.0f;
  // Rows weighed by the depth sensor's noise beyond depth_noise_ref_m, as icp's (IcpOptions::depth_noise_ref_m;
  // hf_reg_depth_noise_scale): a point at depth z > ref counts (ref / z)^4 of a nearer one and the robust kernel
  // sees its distance scaled by (ref / z)^2. 0: every row alike, the default (measured through the pipeline's
  // hand-over on 7-Scenes: bench/results/accuracy/ate_levers.md).
  float depth_noise_ref_m = 0.0f;
  // The model's confidence in the residual (issue 34, item 4): a row weighed by min(1, w / confidence_weight), w
  // the fewest observations of its cell's eight voxels (TSDF weight units), so surfaces seen once or twice pull
  // less than settled ones. 0: off, the default.
  float confidence_weight = 0.0f;
  // The volume the method fuses the reference into when no map was set (pairwise use). 6 voxels, not the map's 4:
  // on the noisy room pair of tests/registration/test_accuracy.cpp 2.81 vs 3.08 mm at finest_level_step 1 (2.67
  // mm at 2; the wider band averages a one-frame field over more depth); 5 mm voxels halve the basin and miss the
  // 9.6 mm motion (8 mm).
  double own_voxel_m = 0.01;
  double own_truncation_vox = 6.0;

  void visit(OptionVisitor& v) override;
  void validate() const override;
};

RegistrationMethod sdf_registration_method();

}  // namespace hf
