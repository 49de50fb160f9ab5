// Rasters people look at: the built-up class raster as PNG with a legend and as GeoTIFF (GDAL, with the class
// colour table and the grid's georeference), a binary mask as PNG. All writes are atomic (temporary + rename);
// failures throw hf::Error naming the file.
#pragma once

#include <string>

#include "lidar/connected_components.h"
#include "lidar/differential_profile.h"
#include "lidar/grid.h"

namespace hf::lidar {

Rgb8 class_colour(BuiltUpClass c);  // none light grey, hamlet red, village green, town purple, city brown (Fig. 5)

// One pixel per cell (north up) and a legend strip below naming each class with its colour.
void write_class_png(const std::string& path, const Image<std::uint8_t>& classes);
// Single-band Byte GeoTIFF of the class codes (0 none .. 4 city) with a colour table; epsg <= 0 leaves the CRS unset.
void write_class_geotiff(const std::string& path, const Image<std::uint8_t>& classes, const Grid& grid, int epsg);
// White on black; with `truth`, cells are coloured TP white, FP red, FN blue.
void write_mask_png(const std::string& path, const Mask& mask, const Mask* truth = nullptr);

}  // namespace hf::lidar
