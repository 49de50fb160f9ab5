// The knobs ndt-p2d and ndt-d2d share (registration/ndt_p2d.h, ndt_d2d.h), and the cell models they build from a
// pyramid level.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <optional>
#include <vector>

#include "registration/frame_pyramid.h"
#include "registration/ndt/ndt_cells.h"
#include "registration/ndt/ndt_newton.h"
#include "registration/registration.h"

namespace hf {

struct NdtOptions : MethodOptionsBase<NdtOptions> {
  // Cell edges, coarsest first (millimetres): the 0.4 / 0.2 / 0.1 m. Newton runs coarse to fine with the
  // driver's iterations per level ([0] the finest, as for pyramids).
  std::vector<int> resolutions_mm = {400, 200, 100};
  double outlier_ratio = 0.55;  // of eq. 6.8 (Magnusson 2007); PCL's default
  // Every stride-th pixel of the finest pyramid level in x and y is a point (of the cell models, and p2d's points).
  int point_stride = 2;
  // p2d: a point is scored against the Gaussians of its cell and its 6 face neighbours (7), or of its cell only (1).
  int neighbours = 7;
  NdtGridOptions grid;

  void visit(OptionVisitor& v) override;
  void validate() const override;
  std::vector<double> resolutions_m() const;
};

// The points an NDT method works on: every point_stride-th valid vertex of a frame's finest level (camera frame,
// metres) and, when the frame has colour, the intensity of its pixel ([0, 1], one per point; empty otherwise).
struct NdtSamples {
  std::vector<Eigen::Vector3d> points;
  std::vector<double> intensity;
  bool has_intensity() const { return !points.empty() && intensity.size() == points.size(); }
};
NdtSamples sample_ndt(const FramePyramidLevel& level, int stride);

// What the NDT methods share around their maths: input checks (no_data for an empty pyramid or a frame without
// enough points, failed for a non-finite guess), the reverse alignment of large motions (verify_large_motion:
// Newton on the NDT score has a basin too) and exceptions turned into a failed result.
using NdtAlign =
    std::function<RegistrationResult(const NdtSamples& current, const NdtSamples& reference, const SE3& T_initial)>;
RegistrationResult ndt_align_checked(const FramePyramid& current, const FramePyramid& reference,
                                     const SE3& T_initial, const RegistrationOptions& options, const NdtAlign& align);
// The solver's settings for one alignment: the driver's iterations, the method's outlier ratio, the current
// points' balanced units, and the terms the finest level could give (rows_possible) and needs (min_terms).
NdtSolveOptions ndt_solve_options(const RegistrationOptions& options, const std::vector<Eigen::Vector3d>& current,
                                  double rows_possible, long min_terms);
// The Registration of an NDT method: its registry name, its options and how one alignment runs on the sampled
// points (solve), wrapped in ndt_align_checked. Validates the options (hf::Error).
using NdtSolve = RegistrationResult (*)(const RegistrationOptions& options, const NdtSamples& current,
                                        const NdtSamples& reference, const SE3& T_initial);
// reads_colour: the solve reads the samples' intensity (Registration::reads_colour).
std::unique_ptr<Registration> make_ndt_registration(const std::string& name, const RegistrationOptions& options,
                                                    NdtSolve solve, bool reads_colour = false);

// balanced_units() of a point set: S = diag(1/L x3, 1 x3), L the RMS distance of the points (>= 1 mm).
Vector6d point_units(const std::vector<Eigen::Vector3d>& points);

}  // namespace hf
