// The NDT cell model (Biber and Strasser 2003; Magnusson 2007; report section 4.1, eq. 62-63): a regular grid of
// Gaussians, each cell holding the mean, covariance and count of the points that fall in it, at several
// resolutions. Built from a frame's points (build_ndt_grid) or directly from the voxel-hashed TSDF's surface blocks
// (registration/ndt/ndt_from_tsdf.h), and read by ndt-p2d and ndt-d2d.
//
// Frames: whatever frame the points are in (a camera frame for frame-to-frame use, the world for the TSDF); cells
// are axis-aligned cubes of edge cell_m in that frame, cell (i, j, k) covering [i, i+1) * cell_m, likewise j, k.
//
// Regularisation (the rule): a cell with fewer than min_points points has no Gaussian (it is not stored). The
// covariance's eigenvalues are floored at max(eigenvalue_floor_ratio * lambda_max, min_sigma_m^2), so a planar or
// linear cell stays invertible and its thin directions stay the sharpest (Magnusson 2009 floors at 1e-3 of the
// largest; 1e-2 here keeps the condition number at 100, where float noise cannot matter).
// Thread-safety: a built grid is immutable; lookups may run concurrently.
#pragma once

#include <cstdint>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace hf {

struct NdtCell {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d Sigma = Eigen::Matrix3d::Zero();      // regularised covariance (metres^2)
  Eigen::Matrix3d Sigma_inv = Eigen::Matrix3d::Zero();  // its inverse
  Eigen::Vector3d eigenvalues = Eigen::Vector3d::Zero();  // of the regularised Sigma, ascending
  Eigen::Matrix3d eigenvectors = Eigen::Matrix3d::Identity();  // columns, matching eigenvalues
  long count = 0;                                       // points in the cell
  // The cell's colour (intensity in [0, 1]) by its weighted mean and variance, for the methods that model it
  // (ndt-color: one component of the cell's colour mixture; mrsmap: the luminance of the surfel); 0 otherwise.
  double colour_mean = 0.0;
  double colour_var = 0.0;
  Eigen::Vector3d normal() const { return eigenvectors.col(0); }  // the thinnest direction
};

struct NdtGridOptions {
  int min_points = 5;                   // fewer: no Gaussian in the cell (Magnusson: 5)
  double eigenvalue_floor_ratio = 1e-2;
  double min_sigma_m = 1e-3;            // 1 mm: below any depth sensor's noise
};

// The weighted moments of the points of one cell (and of their colours, when given), from which a cell is made.
struct NdtMoments {
  double w = 0.0;
  long n = 0;
  Eigen::Vector3d s = Eigen::Vector3d::Zero();
  Eigen::Matrix3d ss = Eigen::Matrix3d::Zero();
  double sc = 0.0, scc = 0.0;  // sum w c, sum w c^2
  void add(const Eigen::Vector3d& p, double weight, double colour = 0.0);
};

// The Gaussian of the moments (eq. 62-63, regularised by the rule above), into cell; false for fewer than
// options.min_points points or a non-finite result.
bool make_ndt_cell(const NdtMoments& m, const NdtGridOptions& options, NdtCell* cell);

// One resolution of the cell model: the Gaussians by integer cell coordinates.
class NdtGrid {
 public:
  NdtGrid() = default;
  NdtGrid(double cell_m, const NdtGridOptions& options) : cell_m_(cell_m), options_(options) {}

  double cell_m() const { return cell_m_; }
  const NdtGridOptions& options() const { return options_; }
  size_t size() const { return cells_.size(); }
  bool empty() const { return cells_.empty(); }

  // The cell containing p, or nullptr (no Gaussian there, or p not finite).
  const NdtCell* find(const Eigen::Vector3d& p) const;
  // The Gaussians that exist of the cell containing p and of its neighbours, into out (cleared first): count 1 (the
  // cell), 7 (and its face neighbours) or 27 (the whole 3x3x3 block, Magnusson's neighbourhood search).
  void neighbourhood(const Eigen::Vector3d& p, int count, std::vector<const NdtCell*>* out) const;
  const std::vector<NdtCell>& cells() const { return cells_; }

  // Accumulation: add points (with weights, e.g. 1, and optionally their colour), then finish() computes the
  // Gaussians. add() after finish() is an error (ignored).
  void add(const Eigen::Vector3d& p, double weight = 1.0, double colour = 0.0);
  void finish();

  // Cells made elsewhere (ndt-color's colour components): the key of the cell containing p (false: p not finite
  // or out of range), and insert() of a cell under a key, which finishes the grid (a key inserted twice keeps the
  // first cell). Insert in ascending key order for a deterministic cells() order.
  bool key_of(const Eigen::Vector3d& p, std::uint64_t* key) const;
  void insert(std::uint64_t key, const NdtCell& cell);

 private:
  static std::uint64_t key(long i, long j, long k);
  bool cell_index(const Eigen::Vector3d& p, long* i, long* j, long* k) const;
  double cell_m_ = 0.1;
  NdtGridOptions options_;
  std::unordered_map<std::uint64_t, NdtMoments> moments_;
  std::unordered_map<std::uint64_t, int> index_;  // key -> cells_ index
  std::vector<NdtCell> cells_;
  bool finished_ = false;
};

// Regularises a covariance by the rule above and fills the cell's Sigma, inverse and eigen-decomposition. False
// for a non-finite covariance.
bool regularise_cell(const Eigen::Matrix3d& covariance, const NdtGridOptions& options, NdtCell* cell);

// The multi-resolution model: one grid per resolution, coarsest first (default 0.4 / 0.2 / 0.1 m).
struct NdtModel {
  std::vector<NdtGrid> levels;
};

// The model of `points` (finite ones only) at each of resolutions_m.
NdtModel build_ndt_model(const std::vector<Eigen::Vector3d>& points, const std::vector<double>& resolutions_m,
                         const NdtGridOptions& options = {});

}  // namespace hf
