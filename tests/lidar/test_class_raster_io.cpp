// The rasters people look at: the GeoTIFF reads back through GDAL with the grid's georeference, the EPSG code,
// the class codes and the colour table; the PNG has the raster plus its legend strip; bad paths name the file.
#include <gtest/gtest.h>

#include <gdal.h>
#include <ogr_srs_api.h>

#include <filesystem>

#include "core/error.h"
#include "io/image_io.h"
#include "lidar/class_raster_io.h"

namespace hf::lidar {
namespace {

TEST(ClassRasterIo, GeoTiffCarriesGridCrsAndClasses) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_lidar_rasters_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Grid grid{0.5, 170000, 895284, 7, 5};  // west 85000, north 447642 (the Delft crop's corner)
  Image<std::uint8_t> classes(7, 5, 0);
  for (int i = 0; i < 7 * 5; ++i) classes.pixels()[i] = static_cast<std::uint8_t>(i % 5);
  const std::string tif = (dir / "classes.tif").string();
  write_class_geotiff(tif, classes, grid, 28992);

  GDALAllRegister();
  GDALDatasetH ds = GDALOpen(tif.c_str(), GA_ReadOnly);
  ASSERT_NE(ds, nullptr);
  EXPECT_EQ(GDALGetRasterXSize(ds), 7);
  EXPECT_EQ(GDALGetRasterYSize(ds), 5);
  double t[6];
  ASSERT_EQ(GDALGetGeoTransform(ds, t), CE_None);
  EXPECT_DOUBLE_EQ(t[0], 85000.0);
  EXPECT_DOUBLE_EQ(t[1], 0.5);
  EXPECT_DOUBLE_EQ(t[3], 447642.0);
  EXPECT_DOUBLE_EQ(t[5], -0.5);
  OGRSpatialReferenceH srs = OSRNewSpatialReference(GDALGetProjectionRef(ds));
  ASSERT_NE(srs, nullptr);
  OSRAutoIdentifyEPSG(srs);
  EXPECT_STREQ(OSRGetAuthorityCode(srs, nullptr), "28992");
  OSRDestroySpatialReference(srs);
  GDALRasterBandH band = GDALGetRasterBand(ds, 1);
  std::vector<std::uint8_t> back(7 * 5);
  ASSERT_EQ(GDALRasterIO(band, GF_Read, 0, 0, 7, 5, back.data(), 7, 5, GDT_Byte, 0, 0), CE_None);
  EXPECT_EQ(back, classes.pixels());
  GDALColorTableH table = GDALGetRasterColorTable(band);
  ASSERT_NE(table, nullptr);
  const GDALColorEntry* hamlet = GDALGetColorEntry(table, 1);
  const Rgb8 expected = class_colour(BuiltUpClass::hamlet);
  EXPECT_EQ(hamlet->c1, expected.r);
  EXPECT_EQ(hamlet->c2, expected.g);
  EXPECT_EQ(hamlet->c3, expected.b);
  GDALClose(ds);

  const std::string png = (dir / "classes.png").string();
  write_class_png(png, classes);
  const ColorImage img = load_color(png);
  EXPECT_EQ(img.height(), 5 + 24);  // the raster and the legend strip
  EXPECT_EQ(img(1, 0), class_colour(BuiltUpClass::hamlet));
  EXPECT_EQ(img(4, 0), class_colour(BuiltUpClass::city));

  EXPECT_THROW(write_class_geotiff((dir / "no_such_folder" / "x.tif").string(), classes, grid, 28992), hf::Error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hf::lidar
