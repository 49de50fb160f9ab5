#include "core/sampling_map.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/error.h"
#include "core/kernels/image_kernels.h"
#include "core/parallel.h"

namespace hf {
namespace {

struct Barycentric {
  double l0 = 0, l1 = 0, l2 = 0;
  bool inside(double eps) const { return l0 >= -eps && l1 >= -eps && l2 >= -eps; }
};

double cross(MapPoint a, MapPoint b, MapPoint c) {
  return (double(b.u) - a.u) * (double(c.v) - a.v) - (double(b.v) - a.v) * (double(c.u) - a.u);
}

// Barycentric coordinates of p in triangle (a, b, c) of positive area.
Barycentric barycentric(MapPoint a, MapPoint b, MapPoint c, double pu, double pv) {
  const double area = cross(a, b, c);
  auto sub_area = [&](MapPoint x, MapPoint y) {
    return (double(y.u) - x.u) * (pv - x.v) - (double(y.v) - x.v) * (pu - x.u);
  };
  Barycentric w;
  w.l0 = sub_area(b, c) / area;
  w.l1 = sub_area(c, a) / area;
  w.l2 = 1.0 - w.l0 - w.l1;
  return w;
}

MapPoint combine(const Barycentric& w, MapPoint a, MapPoint b, MapPoint c) {
  return {float(w.l0 * a.u + w.l1 * b.u + w.l2 * c.u), float(w.l0 * a.v + w.l1 * b.v + w.l2 * c.v)};
}

// Corner indices (i, j offsets) of the two triangles of a cell: (00, 10, 01) and (11, 01, 10).
constexpr int kTri[2][3][2] = {{{0, 0}, {1, 0}, {0, 1}}, {{1, 1}, {0, 1}, {1, 0}}};

}  // namespace

MapPoint SamplingMap::uniform_node(int i, int j) const {
  return {float(-0.5 + double(i) * width_ / cells_x_), float(-0.5 + double(j) * height_ / cells_y_)};
}

SamplingMap SamplingMap::identity(int width, int height, int cells_x, int cells_y) {
  const std::vector<float> ones(size_t(std::max(0, cells_x * cells_y)), 1.0f);
  return from_region_rates(width, height, cells_x, cells_y, ones);
}

SamplingMap SamplingMap::from_region_rates(int width, int height, int cells_x, int cells_y,
                                           const std::vector<float>& rates) {
  if (width < 1 || height < 1 || cells_x < 1 || cells_y < 1)
    throw Error("sampling map: image " + std::to_string(width) + "x" + std::to_string(height) + " with " +
                std::to_string(cells_x) + "x" + std::to_string(cells_y) + " cells: all must be >= 1");
  if (rates.size() != size_t(cells_x) * cells_y)
    throw Error("sampling map: " + std::to_string(rates.size()) + " region rates for " + std::to_string(cells_x) +
                "x" + std::to_string(cells_y) + " cells");
  std::vector<double> column(size_t(cells_x), 0.0), row(size_t(cells_y), 0.0);
  for (int j = 0; j < cells_y; ++j)
    for (int i = 0; i < cells_x; ++i) {
      const float r = rates[size_t(j) * cells_x + i];
      if (!(std::isfinite(r) && r > 0.0f))
        throw Error("sampling map: region rate (" + std::to_string(i) + ", " + std::to_string(j) +
                    ") must be finite and > 0, got " + std::to_string(r));
      column[size_t(i)] = std::max(column[size_t(i)], double(r));
      row[size_t(j)] = std::max(row[size_t(j)], double(r));
    }
  // Cumulative CoNUS edges of the columns / rows, scaled so the last edge lands on a whole pixel count.
  auto edges = [](const std::vector<double>& rate, double cell_px, int* conus_px) {
    std::vector<double> e(rate.size() + 1, 0.0);
    for (size_t k = 0; k < rate.size(); ++k) e[k + 1] = e[k] + rate[k] * cell_px;
    *conus_px = std::max(1, int(std::lround(e.back())));
    const double s = *conus_px / e.back();
    for (double& x : e) x = -0.5 + x * s;
    e.back() = *conus_px - 0.5;
    return e;
  };
  int conus_width = 0, conus_height = 0;
  const std::vector<double> eu = edges(column, double(width) / cells_x, &conus_width);
  const std::vector<double> ev = edges(row, double(height) / cells_y, &conus_height);
  std::vector<MapPoint> nodes(size_t(cells_x + 1) * (cells_y + 1));
  for (int j = 0; j <= cells_y; ++j)
    for (int i = 0; i <= cells_x; ++i)
      nodes[size_t(j) * (cells_x + 1) + i] = {float(eu[size_t(i)]), float(ev[size_t(j)])};
  return from_nodes(width, height, conus_width, conus_height, cells_x, cells_y, std::move(nodes));
}

SamplingMap SamplingMap::from_nodes(int width, int height, int conus_width, int conus_height, int cells_x,
                                    int cells_y, std::vector<MapPoint> nodes) {
  SamplingMap m;
  m.width_ = width, m.height_ = height, m.conus_width_ = conus_width, m.conus_height_ = conus_height;
  m.cells_x_ = cells_x, m.cells_y_ = cells_y;
  m.nodes_ = std::move(nodes);
  m.validate();
  return m;
}

void SamplingMap::validate() const {
  if (width_ < 1 || height_ < 1 || conus_width_ < 1 || conus_height_ < 1 || cells_x_ < 1 || cells_y_ < 1)
    throw Error("sampling map: image, CoNUS image and cell counts must all be >= 1");
  if (nodes_.size() != size_t(cells_x_ + 1) * (cells_y_ + 1))
    throw Error("sampling map: " + std::to_string(nodes_.size()) + " nodes for " + std::to_string(cells_x_) + "x" +
                std::to_string(cells_y_) + " cells (expected (cells_x + 1) (cells_y + 1))");
  const float tol = 1e-3f;
  for (int j = 0; j <= cells_y_; ++j)
    for (int i = 0; i <= cells_x_; ++i) {
      const MapPoint p = node(i, j);
      const bool bad = !std::isfinite(p.u) || !std::isfinite(p.v) ||
                       (i == 0 && std::fabs(p.u + 0.5f) > tol) ||
                       (i == cells_x_ && std::fabs(p.u - (conus_width_ - 0.5f)) > tol) ||
                       (j == 0 && std::fabs(p.v + 0.5f) > tol) ||
                       (j == cells_y_ && std::fabs(p.v - (conus_height_ - 0.5f)) > tol);
      if (bad)
        throw Error("sampling map: node (" + std::to_string(i) + ", " + std::to_string(j) +
                    ") is not finite or a border node off the CoNUS border");
    }
  for (int j = 0; j < cells_y_; ++j)
    for (int i = 0; i < cells_x_; ++i)
      for (const auto& t : kTri) {
        if (!(cross(node(i + t[0][0], j + t[0][1]), node(i + t[1][0], j + t[1][1]), node(i + t[2][0], j + t[2][1])) >
              0.0))
          throw Error("sampling map: cell (" + std::to_string(i) + ", " + std::to_string(j) +
                      ") is folded over (a triangle of non-positive area): the map would not be coherent");
      }
}

bool SamplingMap::distort(MapPoint uniform, MapPoint* conus) const {
  if (!(uniform.u >= -0.5f && uniform.u <= width_ - 0.5f && uniform.v >= -0.5f && uniform.v <= height_ - 0.5f))
    return false;
  const double gx = (double(uniform.u) + 0.5) * cells_x_ / width_, gy = (double(uniform.v) + 0.5) * cells_y_ / height_;
  const int i = std::clamp(int(std::floor(gx)), 0, cells_x_ - 1), j = std::clamp(int(std::floor(gy)), 0, cells_y_ - 1);
  const double fx = gx - i, fy = gy - j;
  // The same barycentric weights as undistort() uses, so the two are exact inverses.
  Barycentric w;
  int t = 0;
  if (fx + fy <= 1.0) {
    w = {1.0 - fx - fy, fx, fy};
  } else {
    t = 1;
    w = {fx + fy - 1.0, 1.0 - fx, 1.0 - fy};
  }
  const auto& c = kTri[t];
  *conus = combine(w, node(i + c[0][0], j + c[0][1]), node(i + c[1][0], j + c[1][1]), node(i + c[2][0], j + c[2][1]));
  return true;
}

bool SamplingMap::undistort(MapPoint conus, MapPoint* uniform) const {
  if (!(conus.u >= -0.5f && conus.u <= conus_width_ - 0.5f && conus.v >= -0.5f && conus.v <= conus_height_ - 0.5f))
    return false;
  // Scan the cells whose bounding box holds the point (a point query; rays() rasterises for whole images).
  for (int j = 0; j < cells_y_; ++j)
    for (int i = 0; i < cells_x_; ++i) {
      const MapPoint a = node(i, j), b = node(i + 1, j), c = node(i, j + 1), d = node(i + 1, j + 1);
      if (conus.u < std::min({a.u, b.u, c.u, d.u}) - 1e-4f || conus.u > std::max({a.u, b.u, c.u, d.u}) + 1e-4f ||
          conus.v < std::min({a.v, b.v, c.v, d.v}) - 1e-4f || conus.v > std::max({a.v, b.v, c.v, d.v}) + 1e-4f)
        continue;
      for (const auto& t : kTri) {
        const Barycentric w = barycentric(node(i + t[0][0], j + t[0][1]), node(i + t[1][0], j + t[1][1]),
                                          node(i + t[2][0], j + t[2][1]), conus.u, conus.v);
        if (!w.inside(1e-7)) continue;
        *uniform = combine(w, uniform_node(i + t[0][0], j + t[0][1]), uniform_node(i + t[1][0], j + t[1][1]),
                           uniform_node(i + t[2][0], j + t[2][1]));
        return true;
      }
    }
  return false;  // unreachable for a validated map: the triangles tile the CoNUS image
}

std::vector<MapPoint> SamplingMap::rays() const {
  std::vector<MapPoint> out(size_t(conus_width_) * conus_height_);
  std::vector<unsigned char> done(out.size(), 0);
  for (int j = 0; j < cells_y_; ++j)
    for (int i = 0; i < cells_x_; ++i)
      for (const auto& t : kTri) {
        const MapPoint a = node(i + t[0][0], j + t[0][1]), b = node(i + t[1][0], j + t[1][1]),
                       c = node(i + t[2][0], j + t[2][1]);
        const int x0 = std::max(0, int(std::ceil(std::min({a.u, b.u, c.u}))));
        const int x1 = std::min(conus_width_ - 1, int(std::floor(std::max({a.u, b.u, c.u}))));
        const int y0 = std::max(0, int(std::ceil(std::min({a.v, b.v, c.v}))));
        const int y1 = std::min(conus_height_ - 1, int(std::floor(std::max({a.v, b.v, c.v}))));
        for (int y = y0; y <= y1; ++y)
          for (int x = x0; x <= x1; ++x) {
            const size_t p = size_t(y) * conus_width_ + x;
            if (done[p]) continue;
            const Barycentric w = barycentric(a, b, c, x, y);
            if (!w.inside(1e-7)) continue;
            out[p] = combine(w, uniform_node(i + t[0][0], j + t[0][1]), uniform_node(i + t[1][0], j + t[1][1]),
                             uniform_node(i + t[2][0], j + t[2][1]));
            done[p] = 1;
          }
      }
  // A pixel centre that fell between two triangles by rounding takes the point query.
  for (size_t p = 0; p < out.size(); ++p)
    if (!done[p]) undistort({float(p % conus_width_), float(p / conus_width_)}, &out[p]);
  return out;
}

namespace {

float sample_clamped(const Image<float>& img, float x, float y) {
  float v = 0.0f;
  x = std::clamp(x, 0.0f, float(img.width() - 1));
  y = std::clamp(y, 0.0f, float(img.height() - 1));
  hf_sample_bilinear(img.data(), img.width(), img.height(), x, y, 0, &v);
  return v;
}

}  // namespace

Image<float> to_conus(const Image<float>& uniform, const SamplingMap& map) {
  if (uniform.width() != map.width() || uniform.height() != map.height())
    throw Error("to_conus: image " + std::to_string(uniform.width()) + "x" + std::to_string(uniform.height()) +
                " does not match the sampling map's " + std::to_string(map.width()) + "x" +
                std::to_string(map.height()));
  const std::vector<MapPoint> rays = map.rays();
  Image<float> out(map.conus_width(), map.conus_height());
  for (size_t p = 0; p < rays.size(); ++p) out.pixels()[p] = sample_clamped(uniform, rays[p].u, rays[p].v);
  return out;
}

Image<float> from_conus(const Image<float>& conus, const SamplingMap& map) {
  if (conus.width() != map.conus_width() || conus.height() != map.conus_height())
    throw Error("from_conus: image " + std::to_string(conus.width()) + "x" + std::to_string(conus.height()) +
                " does not match the sampling map's CoNUS size " + std::to_string(map.conus_width()) + "x" +
                std::to_string(map.conus_height()));
  Image<float> out(map.width(), map.height());
  parallel_for_rows(map.height(), [&](int y) {
    for (int x = 0; x < map.width(); ++x) {
      MapPoint d;
      map.distort({float(x), float(y)}, &d);
      out(x, y) = sample_clamped(conus, d.u, d.v);
    }
  });
  return out;
}

}  // namespace hf
