// "gicp": Generalized ICP (Segal et al. 2009), plane-to-plane, as a per-pixel method on the Gauss-Newton driver
// (report section 3.4's argument for the GPU: neighbourhoods and correspondences in image space). Per-pixel
// residual: registration/kernels/gicp_kernel.h. Works on geometry only.
//
// Per level, before its iterations, every valid vertex of both frames gets a covariance from its image-space
// neighbourhood (gicp_covariances below); the rows are then a pure per-pixel kernel like icp's, on every backend.
#pragma once

#include "registration/kernels/gicp_kernel.h"
#include "registration/registration.h"

namespace hf {

// The measurements behind the defaults: bench/results/registration.md ("gicp defaults").
struct GicpOptions : MethodOptionsBase<GicpOptions> {
  // Correspondence gates, as icp's (projective association; a pair further apart or with normals further apart
  // is not a correspondence).
  float max_dist_m = 0.1f;
  float max_normal_angle_deg = 30.0f;
  // Segal's epsilon: the covariance's eigenvalue along the normal, against 1 along the surface. Segal's 1e-3
  // trusts the normals of real 320x240 depth too much (a pair whose normals differ by a few degrees loses most of
  // its weight along them): TUM fr1/rpy 0-149 through the pipeline, ATE 26.3 / 6.5 / 7.8 cm at 1e-3 / 1e-2 / 1e-1
  // (icp 6.9 cm); reported on the other sequences in bench/results/registration.md ("gicp").
  float gicp_epsilon = 1e-2f;
  // The neighbourhood of a pixel: the valid vertices of its (2 r + 1)^2 window within gicp_neighbour_gate times
  // the window's footprint r z / f of the centre (so no neighbourhood spans a depth edge); fewer than
  // gicp_min_neighbours of them, or a neighbourhood that is a line (middle eigenvalue below 1e-2 of the
  // largest), gives no covariance and no row.
  int gicp_window_px = 2;
  float gicp_neighbour_gate = 4.0f;
  int gicp_min_neighbours = 6;
  // IRLS weight of |r| (metres along the normal, see the kernel header): Huber with k = 1 cm, or Student-t.
  RobustKernel robust_gicp = RobustKernel::huber;
  float huber_gicp_m = 0.01f;
  float t_sigma_gicp_m = 0.01f;
  float t_dof_gicp = 5.0f;

  // Rows at the finest level only for every step-th current pixel in x and y (coarser levels use every pixel; the
  // reference keeps every pixel's covariance), as photometric's finest_level_photometric_step: the covariances
  // and the three rows per pixel cost ~30x icp's one (bench/results/registration.md, "gicp").
  int finest_level_gicp_step = 2;

  void visit(OptionVisitor& v) override;
  void validate() const override;
  hf_gicp_params kernel_params() const;
};

// Segal's regularised covariances of a vertex map into two hf_float4 maps (layout in gicp_kernel.h; w of b is 1
// where valid, every field 0 where not). Deterministic, parallel over rows; a and b are resized.
// step > 1: only pixels with x and y multiples of step get one (the others are invalid).
void gicp_covariances(const VertexMap& vertices, const PinholeCamera& camera, const GicpOptions& options,
                      std::vector<hf_float4>* a, std::vector<hf_float4>* b, int step = 1);

RegistrationMethod gicp_registration_method();

}  // namespace hf
