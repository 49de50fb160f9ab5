#include "lidar/class_raster_io.h"

#include <gdal.h>
#include <cpl_conv.h>
#include <ogr_srs_api.h>

#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "lidar/gdal_errors.h"

namespace hf::lidar {

Rgb8 class_colour(BuiltUpClass c) {
  switch (c) {
    case BuiltUpClass::hamlet: return {220, 40, 40};
    case BuiltUpClass::village: return {40, 170, 60};
    case BuiltUpClass::town: return {140, 60, 180};
    case BuiltUpClass::city: return {130, 80, 30};
    default: return {235, 235, 235};
  }
}

namespace {

constexpr int kLegendRows = 24, kLegendWidth = 5 * 90;

// The legend strip below the classes: a swatch and the name of each class, on white.
cv::Mat legend(int width) {
  cv::Mat bgr(kLegendRows, width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int k = 0; k <= kBuiltUpClasses; ++k) {
    const auto cls = static_cast<BuiltUpClass>(k);
    const Rgb8 c = class_colour(cls);
    const int x0 = 4 + k * 90, y0 = 4;
    cv::rectangle(bgr, cv::Rect(x0, y0, 16, 16), cv::Scalar(c.b, c.g, c.r), cv::FILLED);
    cv::rectangle(bgr, cv::Rect(x0, y0, 16, 16), cv::Scalar(0, 0, 0), 1);
    cv::putText(bgr, class_name(cls), cv::Point(x0 + 20, y0 + 13), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  return bgr;
}

// buildings.png's colours and its legend. One legend whether or not footprints were compared (red and blue then do
// not occur): a tiled merge without the footprints writes the single run's file byte for byte.
const Rgb8 kBuilding{255, 255, 255}, kNothing{0, 0, 0}, kFalsePositive{230, 40, 40}, kMissed{40, 90, 230};
struct Swatch {
  const char* name;
  Rgb8 colour;
};
const Swatch kMaskLegend[] = {{"building", kBuilding},
                              {"no building", kNothing},
                              {"building outside the footprints (FP)", kFalsePositive},
                              {"footprint missed (FN)", kMissed}};

int text_width(const char* s) {
  int baseline = 0;
  return cv::getTextSize(s, cv::FONT_HERSHEY_SIMPLEX, 0.4, 1, &baseline).width;
}

// The swatches' strip: a square and the name of each, left to right on white; its width (legend_width) decides the
// PNG's least width, so no name is cut off.
template <size_t N>
int legend_width(const Swatch (&entries)[N]) {
  int w = 4;
  for (const Swatch& e : entries) w += 20 + text_width(e.name) + 14;
  return w;
}

template <size_t N>
cv::Mat swatch_strip(int width, const Swatch (&entries)[N]) {
  cv::Mat bgr(kLegendRows, width, CV_8UC3, cv::Scalar(255, 255, 255));
  int x0 = 4;
  for (const Swatch& e : entries) {
    cv::rectangle(bgr, cv::Rect(x0, 4, 16, 16), cv::Scalar(e.colour.b, e.colour.g, e.colour.r), cv::FILLED);
    cv::rectangle(bgr, cv::Rect(x0, 4, 16, 16), cv::Scalar(0, 0, 0), 1);
    cv::putText(bgr, e.name, cv::Point(x0 + 20, 17), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1,
                cv::LINE_AA);
    x0 += 20 + text_width(e.name) + 14;
  }
  return bgr;
}

int mask_legend_width() { return legend_width(kMaskLegend); }

void append_rows(PngStream& png, std::vector<Rgb8>& line, const cv::Mat& strip) {
  for (int y = 0; y < strip.rows; ++y) {
    for (int x = 0; x < strip.cols; ++x) {
      const cv::Vec3b p = strip.at<cv::Vec3b>(y, x);
      line[size_t(x)] = {p[2], p[1], p[0]};
    }
    png.row(line.data());
  }
}

}  // namespace

ClassPngWriter::ClassPngWriter(const std::string& path, int width, int height)
    : width_(width), png_(path, std::max(width, kLegendWidth), height + kLegendRows),
      line_(static_cast<size_t>(std::max(width, kLegendWidth)), Rgb8{255, 255, 255}) {}

void ClassPngWriter::rows(const Image<std::uint8_t>& band) {
  for (int y = 0; y < band.height(); ++y) {
    for (int x = 0; x < width_; ++x) line_[x] = class_colour(static_cast<BuiltUpClass>(band(x, y)));
    png_.row(line_.data());
  }
}

void ClassPngWriter::close() {
  append_rows(png_, line_, legend(static_cast<int>(line_.size())));
  png_.close();
}

void check_epsg(int epsg, const std::string& what) {
  if (epsg == 0) return;
  // EPSG codes are positive and below 10^6 (the registry's largest is six digits); PROJ is asked for the rest.
  bool known = epsg > 0 && epsg < 1000000;
  if (known) {
    const QuietGdal quiet;  // PROJ's own "crs not found" line would be a second message
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    known = OSRImportFromEPSG(srs, epsg) == OGRERR_NONE;
    OSRDestroySpatialReference(srs);
  }
  if (!known) throw Error(what + ": EPSG:" + std::to_string(epsg) + " is not a coordinate reference system GDAL knows");
}

ClassGeoTiffWriter::ClassGeoTiffWriter(const std::string& path, const Grid& grid, int epsg)
    : path_(path), width_(grid.width), height_(grid.height) {
  if (grid.width <= 0 || grid.height <= 0) throw Error(path + ": cannot write an empty class raster");
  GDALAllRegister();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  if (!driver) throw Error(path + ": GDAL has no GTiff driver");
  const QuietGdal quiet;
  // Rasters over 4 GB need BigTIFF; IF_SAFER decides from the size, so the choice is the same for any band split.
  char* options[] = {const_cast<char*>("COMPRESS=DEFLATE"), const_cast<char*>("BIGTIFF=IF_SAFER"), nullptr};
  GDALDatasetH ds = GDALCreate(driver, path.c_str(), grid.width, grid.height, 1, GDT_Byte, options);
  if (!ds) throw Error(path + ": GDAL cannot create it" + QuietGdal::why(""));
  dataset_ = ds;
  double transform[6] = {grid.west(), grid.cell_m, 0, grid.north(), 0, -grid.cell_m};
  GDALSetGeoTransform(ds, transform);
  if (epsg != 0) {
    check_epsg(epsg, path);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(nullptr);
    if (OSRImportFromEPSG(srs, epsg) == OGRERR_NONE) {
      char* wkt = nullptr;
      OSRExportToWkt(srs, &wkt);
      GDALSetProjection(ds, wkt);
      CPLFree(wkt);
    }
    OSRDestroySpatialReference(srs);
  }
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  GDALColorTableH table = GDALCreateColorTable(GPI_RGB);
  for (int k = 0; k <= kBuiltUpClasses; ++k) {
    const Rgb8 c = class_colour(static_cast<BuiltUpClass>(k));
    const GDALColorEntry e{c.r, c.g, c.b, 255};
    GDALSetColorEntry(table, k, &e);
  }
  GDALSetRasterColorTable(band, table);
  GDALDestroyColorTable(table);
  int block_x = 0, block_y = 0;
  GDALGetBlockSize(band, &block_x, &block_y);
  block_rows_ = std::max(1, block_y);
}

ClassGeoTiffWriter::~ClassGeoTiffWriter() {
  if (dataset_) {
    const QuietGdal quiet;
    GDALClose(static_cast<GDALDatasetH>(dataset_));
  }
}

// Writes the pending whole strips (all pending rows at the end), so GDAL compresses and places every strip once,
// in order, whatever the callers' bands were.
void ClassGeoTiffWriter::flush_rows() {
  const int pending = static_cast<int>(pending_.size() / size_t(width_));
  const int n = written_ + pending == height_ ? pending : pending / block_rows_ * block_rows_;
  if (n == 0) return;
  const QuietGdal quiet;
  GDALRasterBandH band = GDALGetRasterBand(static_cast<GDALDatasetH>(dataset_), 1);
  if (GDALRasterIO(band, GF_Write, 0, written_, width_, n, pending_.data(), width_, n, GDT_Byte, 0, 0) != CE_None)
    throw Error(path_ + ": GDAL failed to write the raster" + QuietGdal::why(""));
  written_ += n;
  pending_.erase(pending_.begin(), pending_.begin() + std::ptrdiff_t(n) * width_);
}

void ClassGeoTiffWriter::rows(const Image<std::uint8_t>& band) {
  if (band.width() != width_ || written_ + pending_.size() / size_t(width_) + size_t(band.height()) > size_t(height_))
    throw Error(path_ + ": band does not fit the raster");
  pending_.insert(pending_.end(), band.data(), band.data() + band.size());
  flush_rows();
}

void ClassGeoTiffWriter::close() {
  flush_rows();
  if (written_ != height_) throw Error(path_ + ": " + std::to_string(written_) + " of " + std::to_string(height_) + " rows written");
  const QuietGdal quiet;
  GDALClose(static_cast<GDALDatasetH>(dataset_));
  dataset_ = nullptr;
  if (CPLGetLastErrorType() >= CE_Failure) throw Error(path_ + ": GDAL failed to write the raster" + QuietGdal::why(""));
}

MaskPngWriter::MaskPngWriter(const std::string& path, int width, int height)
    : png_(path, std::max(width, mask_legend_width()), height + kLegendRows),
      line_(static_cast<size_t>(std::max(width, mask_legend_width())), Rgb8{255, 255, 255}) {}

void MaskPngWriter::rows(const Mask& band, const Mask* truth) {
  for (int y = 0; y < band.height(); ++y) {
    for (int x = 0; x < band.width(); ++x) {
      const bool m = band(x, y) != 0;
      if (!truth) {
        line_[x] = m ? kBuilding : kNothing;
        continue;
      }
      const bool t = (*truth)(x, y) != 0;
      line_[x] = m && t ? kBuilding : m ? kFalsePositive : t ? kMissed : kNothing;
    }
    png_.row(line_.data());
  }
}

void MaskPngWriter::close() {
  const int width = static_cast<int>(line_.size());
  append_rows(png_, line_, swatch_strip(width, kMaskLegend));
  png_.close();
}

void write_class_png(const std::string& path, const Image<std::uint8_t>& classes) {
  if (classes.empty()) throw Error(path + ": cannot write an empty class raster");
  write_path_atomically(path, [&](const std::string& tmp) {
    ClassPngWriter w(tmp, classes.width(), classes.height());
    w.rows(classes);
    w.close();
  });
}

void write_class_geotiff(const std::string& path, const Image<std::uint8_t>& classes, const Grid& grid, int epsg) {
  if (classes.empty()) throw Error(path + ": cannot write an empty class raster");
  write_path_atomically(path, [&](const std::string& tmp) {
    ClassGeoTiffWriter w(tmp, grid, epsg);
    w.rows(classes);
    w.close();
  });
}

void write_mask_png(const std::string& path, const Mask& mask, const Mask* truth) {
  if (mask.empty()) throw Error(path + ": cannot write an empty mask");
  write_path_atomically(path, [&](const std::string& tmp) {
    MaskPngWriter w(tmp, mask.width(), mask.height());
    w.rows(mask, truth);
    w.close();
  });
}

}  // namespace hf::lidar
