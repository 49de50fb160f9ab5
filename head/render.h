// A headless CPU rasteriser for looking at results: the mesh seen orthographically along a view direction,
// z-buffered, Lambert-shaded, coloured per vertex, with markers (control points) drawn on top. It stands in for
// the viewer's offscreen renderer, which does not exist yet (issue 21).
//
// Frames: `R_view_mesh` rotates mesh coordinates into the view frame, x right, y up, looking down -z (the viewer
// sits at +z). The image is fitted to the projected bounding box of the mesh with a margin. Markers hidden behind
// the surface are drawn hollow.
#pragma once

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "core/image.h"
#include "io/mesh.h"

namespace hf::head {

struct RenderMarker {
  Eigen::Vector3f position;  // mesh frame
  Rgb8 color{0, 0, 0};
  std::string label;  // drawn beside the marker when non-empty
};

struct RenderOptions {
  int width_px = 800;
  int height_px = 800;
  Rgb8 background{255, 255, 255};
};

// Vertex colours come from `colors` (one per vertex), else the mesh's own, else grey.
cv::Mat render_mesh(const TriangleMesh& mesh, const Eigen::Matrix3f& R_view_mesh, const std::vector<Rgb8>& colors,
                    const std::vector<RenderMarker>& markers, const RenderOptions& options = {});

// Several views side by side (the same colours and markers), one image.
cv::Mat render_views(const TriangleMesh& mesh, const std::vector<Eigen::Matrix3f>& R_view_mesh,
                     const std::vector<Rgb8>& colors, const std::vector<RenderMarker>& markers,
                     const RenderOptions& options = {});

// Legends under a rendered image (BGR), returned as a new, taller image of the same width on white:
// - swatches: a filled square and a name per entry, in rows wrapped to the width (class colours);
// - a colour bar: `map` sampled from `lo` to `hi` left to right, ticks labelled at lo, the middle and hi with
//   `unit`, the caption above it, and optional swatches after it for colours outside the bar (e.g. "not evaluated").
// Text is OpenCV's Hershey font; every entry fits the width or wraps, so nothing is cut off.
struct LegendEntry {
  std::string name;
  Rgb8 color;
};
cv::Mat with_swatch_legend(const cv::Mat& image, const std::vector<LegendEntry>& entries);
cv::Mat with_color_bar(const cv::Mat& image, double lo, double hi, Rgb8 (*map)(double value, double lo, double hi),
                       const std::string& caption, const std::string& unit,
                       const std::vector<LegendEntry>& extra = {});

// Writes a BGR image as PNG through a temporary file (core/atomic_file.h); hf::Error naming the file on failure.
void write_png(const std::string& path, const cv::Mat& image);

}  // namespace hf::head
