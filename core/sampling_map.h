// The sampling map of Popescu et al.'s flexible pinhole camera (FPC), "A Flexible Pinhole Camera Model for
// Coherent Nonuniform Sampling": a (cells_x + 1) x (cells_y + 1) mesh of nodes, regular over the uniform (planar
// pinhole, PPC) image and distorted over the CoNUS image, so that a region whose cells are larger in the CoNUS
// image is sampled at a higher rate. Rays still leave one centre and the map is continuous, so straight lines
// stay connected (coherent non-uniform sampling).
//
// Coordinates are pixels with pixel centres at integers (TUM / KinectFusion convention): the uniform image spans
// [-0.5, width - 0.5] x [-0.5, height - 0.5], the CoNUS image [-0.5, conus_width - 0.5] x [...]. Uniform node
// (i, j) sits at (-0.5 + i width / cells_x, -0.5 + j height / cells_y).
//
// As the paper's modified FPC does, every cell is split into two triangles (along its 10-01 diagonal) and the
// map is barycentric on each: then the forward map (distort, the paper's Figure 3) and its inverse (undistort,
// the ray of a CoNUS pixel) are exact inverses, and rays() finds every CoNUS pixel's ray by rasterising the
// distorted mesh (the paper's Figure 5) instead of inverting bilinear interpolation.
//
// Construction validates coherence: the border nodes lie on the CoNUS border and no triangle is folded over
// (positive area), else hf::Error naming the node or triangle. Thread-safety: immutable after construction.
#pragma once

#include <vector>

#include "core/image.h"

namespace hf {

struct MapPoint {
  float u = 0.0f, v = 0.0f;
};

class SamplingMap {
 public:
  // The identity camera: CoNUS image = uniform image.
  static SamplingMap identity(int width, int height, int cells_x, int cells_y);

  // Per-region sampling rates: `rates` (cells_y rows of cells_x, row-major) is the linear rate wanted in each
  // cell, CoNUS pixels per uniform pixel along each axis (1 = full resolution, 0.5 = half; > 0). The map is the
  // tensor product of a column rate (the largest rate in the column) and a row rate (the largest in the row), so
  // every region gets at least its rate; the CoNUS image is sum(column rates) x sum(row rates) cells wide and
  // high, rounded to whole pixels (at least 1).
  static SamplingMap from_region_rates(int width, int height, int cells_x, int cells_y,
                                       const std::vector<float>& rates);

  // Explicit distorted nodes ((cells_x + 1) (cells_y + 1), row-major), e.g. from the paper's mass-spring system or
  // a linear combination of maps. Validated as above.
  static SamplingMap from_nodes(int width, int height, int conus_width, int conus_height, int cells_x, int cells_y,
                                std::vector<MapPoint> nodes);

  int width() const { return width_; }
  int height() const { return height_; }
  int conus_width() const { return conus_width_; }
  int conus_height() const { return conus_height_; }
  int cells_x() const { return cells_x_; }
  int cells_y() const { return cells_y_; }
  const MapPoint& node(int i, int j) const { return nodes_[size_t(j) * (cells_x_ + 1) + i]; }
  MapPoint uniform_node(int i, int j) const;

  // Uniform image point -> CoNUS image point; false (output untouched) outside the uniform image.
  bool distort(MapPoint uniform, MapPoint* conus) const;
  // CoNUS image point -> the uniform image point whose PPC ray it samples; false outside the CoNUS image.
  bool undistort(MapPoint conus, MapPoint* uniform) const;

  // FPC::Rays: the uniform point of every CoNUS pixel centre, conus_width * conus_height, row-major.
  std::vector<MapPoint> rays() const;

 private:
  void validate() const;
  int width_ = 0, height_ = 0, conus_width_ = 0, conus_height_ = 0, cells_x_ = 0, cells_y_ = 0;
  std::vector<MapPoint> nodes_;
};

// FPC::Render(I): the CoNUS image of a uniform image, each CoNUS pixel the bilinear sample of `uniform` at its
// ray's uniform point (the paper's Figure 7).
Image<float> to_conus(const Image<float>& uniform, const SamplingMap& map);

// Resampling a regular image from a CoNUS image with the same PPC (the paper's Figure 8): each uniform pixel is
// the bilinear sample of `conus` at its distorted point.
Image<float> from_conus(const Image<float>& conus, const SamplingMap& map);

}  // namespace hf
