#include "lidar/footprints.h"

#include <gdal.h>
#include <ogr_api.h>

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <memory>

#include "core/error.h"
#include "core/regular_path.h"
#include "lidar/gdal_errors.h"

namespace hf::lidar {
namespace {

void add_polygon(OGRGeometryH geometry, std::vector<Polygon>& out) {
  Polygon p;
  for (int r = 0; r < OGR_G_GetGeometryCount(geometry); ++r) {
    OGRGeometryH ring = OGR_G_GetGeometryRef(geometry, r);
    Ring pts;
    for (int i = 0; i < OGR_G_GetPointCount(ring); ++i) pts.push_back({OGR_G_GetX(ring, i), OGR_G_GetY(ring, i)});
    if (pts.size() >= 3) p.rings.push_back(std::move(pts));
  }
  if (!p.rings.empty()) out.push_back(std::move(p));
}

}  // namespace

std::vector<Polygon> read_footprints(const std::string& path, const std::string& layer_name, const Grid* extent, int* skipped) {
  // GDAL opens the path itself and would block forever on a FIFO; folders stay allowed (shapefile folders).
  require_regular_path(path, "footprint file", true);
  GDALAllRegister();
  const QuietGdal quiet;
  const std::unique_ptr<void, void (*)(GDALDatasetH)> ds(
      GDALOpenEx(path.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY, nullptr, nullptr, nullptr), [](GDALDatasetH h) { GDALClose(h); });
  if (!ds) throw Error(path + ": GDAL cannot open it as vector data" + QuietGdal::why(" (no vector driver recognises it)"));
  OGRLayerH layer = layer_name.empty() ? GDALDatasetGetLayer(ds.get(), 0) : GDALDatasetGetLayerByName(ds.get(), layer_name.c_str());
  if (!layer) throw Error(path + ": no layer " + (layer_name.empty() ? std::string("at all") : "'" + layer_name + "'"));
  if (extent)
    OGR_L_SetSpatialFilterRect(layer, extent->west(), extent->north() - extent->height * extent->cell_m,
                               extent->west() + extent->width * extent->cell_m, extent->north());
  OGR_L_ResetReading(layer);
  std::vector<Polygon> out;
  int other = 0;
  while (OGRFeatureH feature = OGR_L_GetNextFeature(layer)) {
    OGRGeometryH g = OGR_F_GetGeometryRef(feature);
    const OGRwkbGeometryType type = g ? wkbFlatten(OGR_G_GetGeometryType(g)) : wkbUnknown;
    if (type == wkbPolygon) {
      add_polygon(g, out);
    } else if (type == wkbMultiPolygon) {
      for (int i = 0; i < OGR_G_GetGeometryCount(g); ++i) add_polygon(OGR_G_GetGeometryRef(g, i), out);
    } else {
      ++other;
    }
    OGR_F_Destroy(feature);
  }
  if (skipped) *skipped = other;
  return out;
}

Mask rasterise_footprints(const std::vector<Polygon>& polygons, const Grid& grid) { return rasterise_footprints(polygons, grid, 0, grid.height); }

Mask rasterise_footprints(const std::vector<Polygon>& polygons, const Grid& grid, int first_row, int rows) {
  Mask out(grid.width, rows, 0);
  const double r = grid.cell_m;
  std::vector<double> crossings;
  for (const Polygon& p : polygons) {
    double lo = 1e300, hi = -1e300;
    for (const Ring& ring : p.rings)
      for (const auto& v : ring) lo = std::min(lo, v[1]), hi = std::max(hi, v[1]);
    // Rows whose centre y = north - (row + 0.5) r lies in [lo, hi].
    const int row0 = std::max(first_row, static_cast<int>(std::floor((grid.north() - hi) / r - 0.5)));
    const int row1 = std::min(first_row + rows - 1, static_cast<int>(std::ceil((grid.north() - lo) / r - 0.5)));
    for (int row = row0; row <= row1; ++row) {
      const double y = grid.north() - (row + 0.5) * r;
      crossings.clear();
      for (const Ring& ring : p.rings)
        for (size_t i = 0; i < ring.size(); ++i) {
          const auto& a = ring[i];
          const auto& b = ring[(i + 1) % ring.size()];
          // Half-open in y so a vertex on the scan line counts once.
          if ((a[1] <= y) != (b[1] <= y)) crossings.push_back(a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]));
        }
      std::sort(crossings.begin(), crossings.end());
      for (size_t i = 0; i + 1 < crossings.size(); i += 2) {
        // Columns whose centre x = west + (col + 0.5) r lies in [x0, x1).
        const double c0 = std::ceil((crossings[i] - grid.west()) / r - 0.5);
        const double c1 = std::ceil((crossings[i + 1] - grid.west()) / r - 0.5) - 1;
        for (double c = std::max(0.0, c0); c <= std::min(double(grid.width - 1), c1); ++c) out(static_cast<int>(c), row - first_row) = 1;
      }
    }
  }
  return out;
}

Mask rasterise_coverage(const std::vector<Polygon>& polygons, const Grid& grid) { return rasterise_coverage(polygons, grid, 0, grid.height); }

Mask rasterise_coverage(const std::vector<Polygon>& polygons, const Grid& grid, int first_row, int rows) {
  double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
  for (const Polygon& p : polygons)
    for (const Ring& ring : p.rings)
      for (const auto& v : ring)
        for (int k = 0; k < 2; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
  Mask out(grid.width, rows, 0);
  for (int row = first_row; row < first_row + rows; ++row) {
    const double y = grid.north() - (row + 0.5) * grid.cell_m;
    if (y < lo[1] || y > hi[1]) continue;
    for (int col = 0; col < grid.width; ++col) {
      const double x = grid.west() + (col + 0.5) * grid.cell_m;
      if (x >= lo[0] && x <= hi[0]) out(col, row - first_row) = 1;
    }
  }
  return out;
}

}  // namespace hf::lidar
