// Cadastral building footprints (Cvirn section 5.1's ground truth) read through GDAL/OGR, so any vector format
// GDAL knows works: the BGT SQLite of the Delft data (table buildingpart, WKB POLYGON, EPSG:28992), GeoPackage,
// Shapefile, GeoJSON. Coordinates must be in the point cloud's CRS; no reprojection is done.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "lidar/connected_components.h"
#include "lidar/grid.h"

namespace hf::lidar {

using Ring = std::vector<std::array<double, 2>>;  // closed or not; (x, y) metres
struct Polygon {
  std::vector<Ring> rings;  // outer ring first, then holes (the even-odd rule makes the order irrelevant)
};

// Polygons and multipolygons of layer `layer` (empty: the first layer) whose envelopes meet `extent` (when given).
// Throws hf::Error naming the file when GDAL cannot open it or the layer is missing. Other geometry types are
// skipped and counted in `skipped` (when given).
std::vector<Polygon> read_footprints(const std::string& path, const std::string& layer = "", const Grid* extent = nullptr,
                                     int* skipped = nullptr);

// The cells of `grid` whose centre lies inside some polygon (even-odd over each polygon's rings).
Mask rasterise_footprints(const std::vector<Polygon>& polygons, const Grid& grid);
// Rows [first_row, first_row + rows) of the same (a band, for the streaming merge: the same cells bit for bit).
Mask rasterise_footprints(const std::vector<Polygon>& polygons, const Grid& grid, int first_row, int rows);

// Where the footprints say anything: the cells whose centre lies in the bounding box of all polygons. A cadastral
// extract cropped to a survey rarely covers the whole point cloud, and outside its extent a missing footprint
// is no evidence; validation counts only these cells.
Mask rasterise_coverage(const std::vector<Polygon>& polygons, const Grid& grid);
Mask rasterise_coverage(const std::vector<Polygon>& polygons, const Grid& grid, int first_row, int rows);

}  // namespace hf::lidar
