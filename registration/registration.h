// Frame registration: the `Registration` interface and its string-keyed registry.
//
//   auto reg = hf::make_registration("combined");          // any of registration_names()
//   hf::RegistrationResult res = reg->align(cur, ref, T_ref_cur_guess);
//   if (res.usable()) T_world_cur = T_world_ref * res.T_ref_cur;
//
// Frames (report eq. 10-11): the result T_ref_cur = delta_T maps points of the current camera (t+1) into the
// reference camera (t): p_ref = T_ref_cur * p_cur. For frame-to-frame tracking the reference is the previous frame;
// for frame-to-model tracking it is the raycast at the previous pose estimate, whose camera frame is then the
// previous camera, so T_world_cur = T_world_ref * T_ref_cur either way.
//
// Never throws from align() and never returns NaN/inf: invalid input, no data and numerical failure come back
// as a status with T_ref_cur = the initial guess.
// Thread-safety: one Registration object per thread (it owns its reduction backend).
#pragma once

#include <array>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "core/se3.h"
#include "registration/frame_pyramid.h"
#include "registration/pixel_selection.h"
#include "registration/reduction.h"

namespace hf {

namespace fusion {
class VoxelBlockGrid;  // fusion/voxel_block_grid.h
}

enum class RegistrationStatus {
  good,        // converged, well conditioned, enough inliers
  poor,        // converged but few inliers or large residuals: usable with care
  degenerate,  // some directions are unconstrained; they kept the initial guess (see degenerate_dims)
  failed,      // diverged, lost correspondences or hit a numerical problem; T_ref_cur = the initial guess
  no_data,     // no valid pixels / correspondences at all; T_ref_cur = the initial guess
};
const char* to_string(RegistrationStatus status);

enum class RobustKernel { none, huber, student_t };

// Visits named option fields: how a caller reads and writes options (e.g. the pipeline's JSON config) without
// knowing any method. Keys are the option names users type; one key names one field.
class OptionVisitor {
 public:
  virtual ~OptionVisitor() = default;
  virtual void operator()(const char* key, int& value) = 0;
  virtual void operator()(const char* key, long& value) = 0;
  virtual void operator()(const char* key, float& value) = 0;
  virtual void operator()(const char* key, double& value) = 0;
  virtual void operator()(const char* key, bool& value) = 0;
  virtual void operator()(const char* key, std::vector<int>& value) = 0;
  virtual void operator()(const char* key, RobustKernel& value) = 0;
};

// An OptionVisitor from any callable v(key, field) with overloads (or a template) for the seven field types.
template <class F>
class OptionVisitorFor final : public OptionVisitor {
 public:
  explicit OptionVisitorFor(F& f) : f_(f) {}
  void operator()(const char* key, int& value) override { f_(key, value); }
  void operator()(const char* key, long& value) override { f_(key, value); }
  void operator()(const char* key, float& value) override { f_(key, value); }
  void operator()(const char* key, double& value) override { f_(key, value); }
  void operator()(const char* key, bool& value) override { f_(key, value); }
  void operator()(const char* key, std::vector<int>& value) override { f_(key, value); }
  void operator()(const char* key, RobustKernel& value) override { f_(key, value); }

 private:
  F& f_;
};

// A method's own knobs (registration/icp.h IcpOptions, ...), with their defaults where they are declared.
class MethodOptions {
 public:
  virtual ~MethodOptions() = default;
  virtual std::unique_ptr<MethodOptions> clone() const = 0;
  virtual void visit(OptionVisitor& v) = 0;  // every knob by its key
  virtual void validate() const = 0;         // hf::Error naming the first bad field
};

// For MethodOptions::validate(): throws hf::Error "registration options: <what>" unless ok.
void require_option(bool ok, const char* what);
inline bool finite_positive(double v) { return v > 0.0 && v < std::numeric_limits<double>::infinity(); }

// Helper for MethodOptions implementations: clone() as a copy.
template <class Derived>
class MethodOptionsBase : public MethodOptions {
 public:
  std::unique_ptr<MethodOptions> clone() const override {
    return std::make_unique<Derived>(static_cast<const Derived&>(*this));
  }
};

// The settings of the Gauss-Newton driver (registration/gauss_newton.h), shared by every method. The numbers
// behind each default: bench/results/registration.md ("Driver defaults").
struct GaussNewtonOptions {
  // Iterations per pyramid level, [0] finest: KinectFusion's 4/5/10 coarse to fine. Its size is the number of
  // levels used (at most the pyramids' levels).
  std::vector<int> iterations = {10, 5, 4};
  // Convergence: stop a level when the step is below both (radians, metres); 1e-5 moves a point at 2 m by
  // ~0.005 px at 640x480.
  double min_step_rotation_rad = 1e-5;
  double min_step_translation_m = 1e-5;
  // Degeneracy (Zhang et al. 2016): eigen-directions of the balanced information with lambda_i < threshold *
  // lambda_max are not updated. 3e-3: 2x above the wall preset's noise floor, 1.7x below the corridor's axis.
  double degeneracy_threshold = 3e-3;
  // Outcome checks.
  long min_inliers = 64;              // fewer at the finest level: no_data (0 rows) or failed
  double poor_inlier_ratio = 0.3;     // below: poor
  double max_translation_m = 0.5;     // |t| of T_guess^-1 T_result beyond: failed (never a wild pose)
  double max_rotation_deg = 45.0;
  // A result that moved more than verify_motion_m or verify_motion_deg from the initial guess is re-checked by
  // aligning the reference onto the current frame, and reported failed unless the loop T_fwd T_rev is within
  // verify_agreement_m / _deg of the identity (5 cm / 10 deg: above every consecutive TUM fr1 pair).
  double verify_motion_m = 0.05;
  double verify_motion_deg = 10.0;
  double verify_agreement_m = 0.01;
  double verify_agreement_deg = 0.5;
  // The last finest-level step must be below these, else the estimate was still sliding: failed (converged
  // real frames end near 1e-4 under changing IRLS weights).
  double max_final_step_translation_m = 2e-3;
  double max_final_step_rotation_rad = 2e-3;
  // Which current pixels give rows on the finest row_selection.levels levels (registration/pixel_selection.h):
  // all (the default), an importance-driven budget per tile, or the same budget spread uniformly. Keys
  // row_selection (0 all, 1 importance, 2 uniform), row_selection_tile_px, row_selection_budget,
  // row_selection_depth_edge_weight, row_selection_levels. Measured in bench/results/fewer_rays_tracking.md.
  PixelSelectionOptions row_selection;
  // Rotation-first alignment (registration/so3_prealign.h, ElasticFusion's SO(3) step) for methods that read
  // colour: Gauss-Newton iterations of the photometric rotation-only fit on the coarsest pyramid levels before the
  // dense solve, [0] for the coarsest; empty = off. The driver's default is off; combined's registry defaults turn
  // it on for align() (wide_basin_so3_iterations(), so3_prealign.h), the SLAM pipeline's settings off
  // (bench/results/accuracy/large_motion.md).
  std::vector<int> so3_iterations;

  void visit(OptionVisitor& v);
  void validate() const;  // hf::Error naming the first bad field
};

// A method's options in force: the driver's settings and the method's own knobs (null for a placeholder, e.g. the
// pipeline's "groundtruth"). Copies deep-copy the method's options.
class RegistrationOptions {
 public:
  RegistrationOptions() = default;
  RegistrationOptions(const GaussNewtonOptions& driver, std::unique_ptr<MethodOptions> method);
  RegistrationOptions(const RegistrationOptions& other);
  RegistrationOptions& operator=(const RegistrationOptions& other);
  RegistrationOptions(RegistrationOptions&&) noexcept = default;
  RegistrationOptions& operator=(RegistrationOptions&&) noexcept = default;

  GaussNewtonOptions driver;

  const MethodOptions* method() const { return method_.get(); }
  MethodOptions* method() { return method_.get(); }
  // The method's options as their type; hf::Error when they are absent or of another method.
  template <class T>
  T& method_as() {
    T* m = dynamic_cast<T*>(method_.get());
    if (m == nullptr) throw_wrong_method();
    return *m;
  }
  template <class T>
  const T& method_as() const {
    return const_cast<RegistrationOptions*>(this)->method_as<T>();
  }
  // The driver's keys, then the method's: one flat namespace (no key appears twice).
  void visit(OptionVisitor& v);
  // The same with a callable f(key, field&), e.g. a generic lambda.
  template <class F>
  void for_each_option(F&& f) {
    OptionVisitorFor<std::remove_reference_t<F>> v(f);
    visit(v);
  }
  // Sets the numeric option `key` when it exists; false when neither the driver nor the method has it.
  bool set(const std::string& key, double value);
  // Throws hf::Error naming the first bad field.
  void validate() const;

 private:
  [[noreturn]] static void throw_wrong_method();
  std::unique_ptr<MethodOptions> method_;
};

// What a key of options written before methods owned their knobs (hashfusion <= cc8db77: one RegistrationOptions
// with every method's keys, as in report.json's config.registration_options) means for options `now` (a method's,
// or the driver's alone). For a former key `now` does not have: the key it was renamed to, or "" when `now` has no
// such knob (drop it); the key itself when `now` has it; std::nullopt when it was never a registration option (an
// error for the caller). Renames: "t_dof" (nu of both terms) is "t_dof_icp" where only the ICP term has a nu,
// "max_dist_m" (also the photometric occlusion gate) is "occlusion_max_depth_m" where only the photometric term
// has that gate; every other former key is dropped by options that do not have it.
std::optional<std::string> migrate_registration_key(const RegistrationOptions& now, const std::string& key);

struct RegistrationResult {
  SE3 T_ref_cur;  // maps current-camera points into the reference camera (delta_T, eq. 10-11)
  RegistrationStatus status = RegistrationStatus::no_data;
  std::vector<int> iterations_per_level;  // [0] finest, as the pyramid; 0 for levels that were skipped
  double final_cost = 0.0;     // sum w r^2 / count at the last finest-level evaluation
  long inliers = 0;            // rows with a correspondence at the last finest-level evaluation
  double inlier_ratio = 0.0;   // inliers / rows possible (valid current pixels; photometric rows only on the
                               // finest_level_photometric_step grid), in [0, 1]
  Matrix6d information = Matrix6d::Zero();  // J^T W J at the solution (finest level), xi = (omega, v) order
  // Eigenvalues (ascending) and condition number (largest / smallest; 0 when singular, never inf) of the
  // information with rotations scaled to displacements at the RMS point distance L (S H S, S = diag(1/L x3, 1 x3)),
  // the matrix the degeneracy test uses.
  Vector6d eigenvalues = Vector6d::Zero();
  double condition_number = 0.0;
  int degenerate_dims = 0;     // eigen-directions below the degeneracy threshold (0..6)
  // Unit eigenvector of eigenvalues(0) in the same balanced units, (omega L, v): the direction the data constrain
  // least. Worth a look when eigenvalues(0) / eigenvalues(5) is small but above the degeneracy threshold (a
  // corridor: its axis), where the estimate along it tends to stay near the initial guess.
  Vector6d weakest_direction = Vector6d::Zero();
  std::string message;         // why the status is not good (one line), empty otherwise
  // For a method whose rows are separate terms (combined: "icp" then "photometric"; DenseMethod::term_names), each
  // term's own J^T W J at the solution (finest level, its term weight included, before the per-direction
  // weighting; same units as `information`) and its rows. Two terms that are each well constrained but pull apart
  // (colour not registered to depth) show as a large cost with both informations strong, and as steps that point
  // apart (slam/colour_check.h reads them). Empty otherwise.
  struct Term {
    std::string name;
    Matrix6d information = Matrix6d::Zero();
    long rows = 0;
    Vector6d gradient = Vector6d::Zero();  // J^T W r of the term at the solution (same evaluation as information)
    double cost = 0.0;                     // its sum of w r^2 there (term weight included, as information)
    // The Gauss-Newton step this term alone would take from the solution, -information^-1 gradient, xi = (omega, v)
    // order; its directions below the driver's degeneracy threshold (balanced units) left at 0.
    Vector6d step = Vector6d::Zero();
  };
  std::vector<Term> terms;

  bool usable() const {
    return status == RegistrationStatus::good || status == RegistrationStatus::poor ||
           status == RegistrationStatus::degenerate;
  }
};

class Registration {
 public:
  virtual ~Registration() = default;
  // Aligns the current pyramid to the reference pyramid starting from T_ref_cur_initial. Both pyramids must have
  // the same camera per level; photometric methods need intensity in both. Never throws.
  virtual RegistrationResult align(const FramePyramid& current, const FramePyramid& reference,
                                   const SE3& T_ref_cur_initial) = 0;
  virtual std::string name() const = 0;
  virtual const RegistrationOptions& options() const = 0;

  // Whether align() reads the frames' intensity (photometric rows, colour distributions, features on the image):
  // a pipeline whose colour turns out not to be registered to its depth (slam/colour_check.h) replaces such a
  // method by a depth-only one.
  virtual bool reads_colour() const { return false; }

  // A method that can align to the map itself (sdf: the TSDF) says so here; set_volume() then hands it the map
  // and the pose of the reference camera in it (T_ref_cur stays relative to that camera), and align() neither
  // reads nor needs the reference pyramid (it may be empty), so a pipeline can skip its tracking raycast. The map
  // must outlive the align() calls and not change during one; nullptr takes it back. Other methods: false, and
  // set_volume() does nothing.
  virtual bool aligns_to_volume() const { return false; }
  virtual void set_volume(const fusion::VoxelBlockGrid* grid, const SE3& T_world_ref) {
    (void)grid;
    (void)T_world_ref;
  }
};

// A registry entry: the name users type, the method's default options, its factory (which validates the options
// and throws hf::Error for options of another method).
struct RegistrationMethod {
  std::string name;
  RegistrationOptions (*defaults)() = nullptr;
  std::unique_ptr<Registration> (*make)(const RegistrationOptions&, std::unique_ptr<ReductionBackend>) = nullptr;
};

// Adds a method at run time (the built-in ones are in registration/methods.def); hf::Error when the name is taken
// or the entry is incomplete. Thread-safe, like the look-ups below.
void register_registration(const RegistrationMethod& method);

// Default options of a registered method; hf::Error for unknown names.
RegistrationOptions default_registration_options(const std::string& name);

// The registry. make_registration throws hf::Error "unknown registration method 'x' (known: ...)" for unknown
// names and the backend registry's error for a bad backend; options are validated.
std::unique_ptr<Registration> make_registration(const std::string& name, const std::string& backend = "cpu");
std::unique_ptr<Registration> make_registration(const std::string& name, const RegistrationOptions& options,
                                                std::unique_ptr<ReductionBackend> backend);
std::vector<std::string> registration_names();  // sorted

}  // namespace hf
