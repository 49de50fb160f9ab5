// Rasters people look at: the built-up class raster as PNG with a legend and as GeoTIFF (GDAL, with the class
// colour table and the grid's georeference), a binary mask as PNG. All writes are atomic (temporary + rename);
// failures throw hf::Error naming the file.
#pragma once

#include <memory>
#include <string>

#include "lidar/connected_components.h"
#include "lidar/differential_profile.h"
#include "lidar/grid.h"
#include "lidar/png_stream.h"

namespace hf::lidar {

Rgb8 class_colour(BuiltUpClass c);  // none light grey, hamlet red, village green, town purple, city brown (Fig. 5)

// One pixel per cell (north up) and a legend strip below naming each class with its colour.
void write_class_png(const std::string& path, const Image<std::uint8_t>& classes);
// hf::Error unless epsg is 0 (no CRS) or a code GDAL's EPSG tables know ("--epsg -5" was ignored, an unknown code
// silently left the GeoTIFF without a CRS); `what` names where the code came from in the message.
void check_epsg(int epsg, const std::string& what);
// Single-band Byte GeoTIFF of the class codes (0 none .. 4 city) with a colour table; epsg 0 leaves the CRS unset,
// an unknown code is an hf::Error (check_epsg).
void write_class_geotiff(const std::string& path, const Image<std::uint8_t>& classes, const Grid& grid, int epsg);
// White on black; with `truth`, cells are coloured TP white, FP red, FN blue. A legend strip below names the colours
// (the image widened to fit it where the mask is narrower).
void write_mask_png(const std::string& path, const Mask& mask, const Mask* truth = nullptr);

// The same three files written band by band, top to bottom (the tiled merge, lidar/tiling.h, never holds the
// whole raster): each writer takes bands of any height (full width) and close() after the last row. The bytes do
// not depend on the band heights, so a merge writes the files of a single run byte for byte. They write to the
// path given (the caller makes it atomic: write_path_atomically); failures throw hf::Error naming it.
class ClassPngWriter {
 public:
  ClassPngWriter(const std::string& path, int width, int height);
  void rows(const Image<std::uint8_t>& band);
  void close();  // appends the legend

 private:
  int width_ = 0;
  PngStream png_;
  std::vector<Rgb8> line_;
};

class ClassGeoTiffWriter {
 public:
  ClassGeoTiffWriter(const std::string& path, const Grid& grid, int epsg);
  ~ClassGeoTiffWriter();
  ClassGeoTiffWriter(const ClassGeoTiffWriter&) = delete;
  ClassGeoTiffWriter& operator=(const ClassGeoTiffWriter&) = delete;
  void rows(const Image<std::uint8_t>& band);
  void close();

 private:
  void flush_rows();
  std::string path_;
  int width_ = 0, height_ = 0, block_rows_ = 1, written_ = 0;
  void* dataset_ = nullptr;                // GDALDatasetH
  std::vector<std::uint8_t> pending_;      // rows not yet written: GDAL gets whole strips only, in order
};

class MaskPngWriter {
 public:
  MaskPngWriter(const std::string& path, int width, int height);
  void rows(const Mask& band, const Mask* truth = nullptr);
  void close();  // appends the legend

 private:
  PngStream png_;
  std::vector<Rgb8> line_;
};

}  // namespace hf::lidar
