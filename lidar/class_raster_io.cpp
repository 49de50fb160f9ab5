#include "lidar/class_raster_io.h"

#include <gdal.h>
#include <cpl_conv.h>
#include <ogr_srs_api.h>

#include <opencv2/imgproc.hpp>

#include "core/atomic_file.h"
#include "core/error.h"
#include "io/image_io.h"
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

void write_class_png(const std::string& path, const Image<std::uint8_t>& classes) {
  if (classes.empty()) throw Error(path + ": cannot write an empty class raster");
  const int legend_h = 24, w = std::max(classes.width(), 5 * 90);
  cv::Mat bgr(classes.height() + legend_h, w, CV_8UC3, cv::Scalar(255, 255, 255));
  for (int y = 0; y < classes.height(); ++y)
    for (int x = 0; x < classes.width(); ++x) {
      const Rgb8 c = class_colour(static_cast<BuiltUpClass>(classes(x, y)));
      bgr.at<cv::Vec3b>(y, x) = cv::Vec3b(c.b, c.g, c.r);
    }
  for (int k = 0; k <= kBuiltUpClasses; ++k) {
    const auto cls = static_cast<BuiltUpClass>(k);
    const Rgb8 c = class_colour(cls);
    const int x0 = 4 + k * 90, y0 = classes.height() + 4;
    cv::rectangle(bgr, cv::Rect(x0, y0, 16, 16), cv::Scalar(c.b, c.g, c.r), cv::FILLED);
    cv::rectangle(bgr, cv::Rect(x0, y0, 16, 16), cv::Scalar(0, 0, 0), 1);
    cv::putText(bgr, class_name(cls), cv::Point(x0 + 20, y0 + 13), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
  }
  ColorImage rgb(bgr.cols, bgr.rows);
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) {
      const cv::Vec3b p = bgr.at<cv::Vec3b>(y, x);
      rgb(x, y) = {p[2], p[1], p[0]};
    }
  write_color_png(path, rgb);
}

void write_class_geotiff(const std::string& path, const Image<std::uint8_t>& classes, const Grid& grid, int epsg) {
  if (classes.empty()) throw Error(path + ": cannot write an empty class raster");
  GDALAllRegister();
  GDALDriverH driver = GDALGetDriverByName("GTiff");
  if (!driver) throw Error(path + ": GDAL has no GTiff driver");
  const QuietGdal quiet;
  write_path_atomically(path, [&](const std::string& tmp) {
    char* options[] = {const_cast<char*>("COMPRESS=DEFLATE"), nullptr};
    GDALDatasetH ds = GDALCreate(driver, tmp.c_str(), classes.width(), classes.height(), 1, GDT_Byte, options);
    if (!ds) throw Error(path + ": GDAL cannot create it" + QuietGdal::why(""));
    double transform[6] = {grid.west(), grid.cell_m, 0, grid.north(), 0, -grid.cell_m};
    GDALSetGeoTransform(ds, transform);
    if (epsg > 0) {
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
    const CPLErr err = GDALRasterIO(band, GF_Write, 0, 0, classes.width(), classes.height(), const_cast<std::uint8_t*>(classes.data()),
                                    classes.width(), classes.height(), GDT_Byte, 0, 0);
    GDALClose(ds);
    if (err != CE_None) throw Error(path + ": GDAL failed to write the raster" + QuietGdal::why(""));
  });
}

void write_mask_png(const std::string& path, const Mask& mask, const Mask* truth) {
  ColorImage rgb(mask.width(), mask.height());
  for (size_t i = 0; i < mask.size(); ++i) {
    const bool m = mask.pixels()[i] != 0;
    if (!truth) {
      rgb.pixels()[i] = m ? Rgb8{255, 255, 255} : Rgb8{0, 0, 0};
      continue;
    }
    const bool t = truth->pixels()[i] != 0;
    rgb.pixels()[i] = m && t ? Rgb8{255, 255, 255} : m ? Rgb8{230, 40, 40} : t ? Rgb8{40, 90, 230} : Rgb8{0, 0, 0};
  }
  write_color_png(path, rgb);
}

}  // namespace hf::lidar
