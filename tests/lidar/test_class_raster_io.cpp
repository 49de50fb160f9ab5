// The rasters people look at: the GeoTIFF reads back through GDAL with the grid's georeference, the EPSG code,
// the class codes and the colour table; the PNG has the raster plus its legend strip; bad paths name the file;
// the PNG row writer round-trips.
#include <gtest/gtest.h>

#include <gdal.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "io/image_io.h"
#include "lidar/class_raster_io.h"
#include "lidar/png_stream.h"

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

std::string bytes_of(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// The band writers of the streaming merge write the whole-image files byte for byte whatever the band heights
// (GeoTIFF strips and PNG IDAT chunks are cut by the writers, not by the callers), on a raster large enough for
// several strips and IDAT chunks; a writer closed short of its rows refuses.
TEST(ClassRasterIo, BandWritersEqualTheWholeImageWriters) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_lidar_bands_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const Grid grid{0.5, 170000, 895284, 613, 301};
  Image<std::uint8_t> classes(grid.width, grid.height, 0);
  Mask mask(grid.width, grid.height, 0), truth(grid.width, grid.height, 0);
  std::uint32_t state = 7;
  for (size_t i = 0; i < classes.size(); ++i) {
    state = state * 1664525u + 1013904223u;  // noise, so the PNG needs several 64 KiB IDAT chunks
    classes.pixels()[i] = static_cast<std::uint8_t>((state >> 24) % 5), mask.pixels()[i] = (state >> 20) & 1, truth.pixels()[i] = (state >> 21) & 1;
  }
  write_class_geotiff((dir / "whole.tif").string(), classes, grid, 28992);
  write_class_png((dir / "whole.png").string(), classes);
  write_mask_png((dir / "whole_mask.png").string(), mask, &truth);
  ASSERT_GT(std::filesystem::file_size(dir / "whole.png"), 65536u);  // two IDAT chunks at least
  const auto band = [](const Image<std::uint8_t>& img, int y0, int rows) {
    Image<std::uint8_t> b(img.width(), rows);
    std::copy_n(img.data() + size_t(y0) * img.width(), b.size(), b.data());
    return b;
  };
  {
    ClassGeoTiffWriter tif((dir / "bands.tif").string(), grid, 28992);
    ClassPngWriter png((dir / "bands.png").string(), grid.width, grid.height);
    MaskPngWriter m((dir / "bands_mask.png").string(), grid.width, grid.height);
    for (int y0 = 0, k = 0; y0 < grid.height; ++k) {
      const int rows = std::min(grid.height - y0, 1 + (k * 37) % 29);  // uneven bands, 1..29 rows
      tif.rows(band(classes, y0, rows)), png.rows(band(classes, y0, rows));
      const Mask t = band(truth, y0, rows);
      m.rows(band(mask, y0, rows), &t);
      y0 += rows;
    }
    tif.close(), png.close(), m.close();
  }
  EXPECT_EQ(bytes_of(dir / "bands.tif"), bytes_of(dir / "whole.tif"));
  EXPECT_EQ(bytes_of(dir / "bands.png"), bytes_of(dir / "whole.png"));
  EXPECT_EQ(bytes_of(dir / "bands_mask.png"), bytes_of(dir / "whole_mask.png"));
  const ColorImage back = load_color((dir / "bands_mask.png").string());
  const Rgb8 expected = mask(0, 0) && truth(0, 0) ? Rgb8{255, 255, 255} : mask(0, 0) ? Rgb8{230, 40, 40} : truth(0, 0) ? Rgb8{40, 90, 230} : Rgb8{0, 0, 0};
  EXPECT_EQ(back(0, 0), expected);
  ClassPngWriter short_png((dir / "short.png").string(), grid.width, grid.height);
  short_png.rows(band(classes, 0, 10));
  EXPECT_THROW(short_png.close(), hf::Error);
  std::filesystem::remove_all(dir);
}


// The PNG rows as libpng writes them (lidar/png_stream.h): noise rows decode (OpenCV's reader) to exactly the pixels
// written, in IDAT chunks of 64 KiB but the last; extra rows, a short close, an empty size, an unopenable path and
// a full disk are hf::Errors naming the file.
TEST(PngStream, RoundTripChunksAndErrors) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_png_stream_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const int W = 301, H = 257;  // 232 KB of noise: at least three IDAT chunks
  std::vector<Rgb8> pixels(size_t(W) * H);
  std::uint32_t state = 11;
  for (Rgb8& p : pixels) {
    state = state * 1664525u + 1013904223u;
    p = {std::uint8_t(state >> 24), std::uint8_t(state >> 16), std::uint8_t(state >> 8)};
  }
  const std::string path = (dir / "noise.png").string();
  {
    PngStream png(path, W, H);
    for (int y = 0; y < H; ++y) png.row(&pixels[size_t(y) * W]);
    EXPECT_THROW(png.row(pixels.data()), hf::Error);  // one row too many
    png.close();
  }
  const ColorImage back = load_color(path);
  ASSERT_EQ(back.width(), W);
  ASSERT_EQ(back.height(), H);
  EXPECT_EQ(back.pixels(), pixels);
  // The chunks: signature, IHDR, IDAT..., IEND; every IDAT but the last exactly 64 KiB.
  const std::string bytes = bytes_of(path);
  ASSERT_EQ(bytes.compare(0, 8, "\x89PNG\r\n\x1a\n"), 0);
  std::vector<std::string> types;
  std::vector<std::uint32_t> idat;
  for (size_t at = 8; at + 12 <= bytes.size();) {
    std::uint32_t n = 0;
    for (int i = 0; i < 4; ++i) n = n << 8 | std::uint8_t(bytes[at + size_t(i)]);
    types.push_back(bytes.substr(at + 4, 4));
    if (types.back() == "IDAT") idat.push_back(n);
    at += 12 + n;
  }
  ASSERT_GE(idat.size(), 3u);
  EXPECT_EQ(types.front(), "IHDR");
  EXPECT_EQ(types.back(), "IEND");
  for (size_t i = 0; i + 1 < idat.size(); ++i) EXPECT_EQ(idat[i], 65536u) << "IDAT " << i;
  EXPECT_LE(idat.back(), 65536u);

  const auto message = [](const auto& make) {
    try {
      make();
    } catch (const hf::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string missing = (dir / "no_such_folder" / "x.png").string();
  EXPECT_NE(message([&] { PngStream p(missing, 4, 4); }).find(missing + ": cannot open"), std::string::npos);
  EXPECT_NE(message([&] { PngStream p(path, 0, 4); }).find(path + ": cannot write an empty PNG"), std::string::npos);
  EXPECT_NE(message([&] {
              PngStream p(path, W, H);
              p.row(pixels.data());
              p.close();
            }).find(path + ": 1 of 257 rows written"),
            std::string::npos);
  if (std::filesystem::exists("/dev/full")) {  // every write fails with ENOSPC
    EXPECT_NE(message([&] {
                PngStream p("/dev/full", W, H);
                for (int y = 0; y < H; ++y) p.row(&pixels[size_t(y) * W]);
                p.close();
              }).find("/dev/full: write failed"),
              std::string::npos);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hf::lidar
