// The LAS reader on files this test writes (every point format x every version that allows it), on malformed
// headers and lying point counts, and on the real files in ../shared/data when present.
#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "core/error.h"
#include "io/las.h"

namespace {

std::vector<hf::LasPoint> random_points(int format, int n, std::uint64_t seed, const hf::LasHeader& h) {
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> coord(-2000000, 2000000), u16(0, 65535), u8(0, 255);
  std::vector<hf::LasPoint> pts(static_cast<size_t>(n));
  const bool extended = format >= 6;
  for (auto& p : pts) {
    // Positions on the integer lattice of the scale, so they survive the write exactly (up to double rounding).
    p.x = coord(rng) * h.scale[0] + h.offset[0];
    p.y = coord(rng) * h.scale[1] + h.offset[1];
    p.z = coord(rng) * h.scale[2] + h.offset[2];
    p.intensity = static_cast<std::uint16_t>(u16(rng));
    p.return_number = static_cast<std::uint8_t>(u8(rng) % (extended ? 16 : 8));
    p.number_of_returns = static_cast<std::uint8_t>(u8(rng) % (extended ? 16 : 8));
    p.classification = static_cast<std::uint8_t>(extended ? u8(rng) : u8(rng) % 32);
    p.synthetic = u8(rng) & 1, p.key_point = u8(rng) & 1, p.withheld = u8(rng) & 1;
    p.overlap = extended && (u8(rng) & 1);
    p.scanner_channel = extended ? static_cast<std::uint8_t>(u8(rng) % 4) : 0;
    p.scan_angle_deg = extended ? static_cast<float>((u16(rng) % 30000 - 15000) * 0.006) : static_cast<float>(u8(rng) % 181 - 90);
    p.user_data = static_cast<std::uint8_t>(u8(rng));
    p.point_source_id = static_cast<std::uint16_t>(u16(rng));
    const bool gps = format == 1 || format >= 3, rgb = format == 2 || format == 3 || format == 5 || format == 7 || format == 8 ||
                                                       format == 10;
    p.gps_time = gps ? u16(rng) * 0.125 : 0.0;
    if (rgb) p.red = static_cast<std::uint16_t>(u16(rng)), p.green = static_cast<std::uint16_t>(u16(rng)), p.blue = static_cast<std::uint16_t>(u16(rng));
    p.nir = (format == 8 || format == 10) ? static_cast<std::uint16_t>(u16(rng)) : 0;
  }
  return pts;
}

hf::LasHeader header_for(int minor, int format) {
  hf::LasHeader h;
  h.version_minor = minor;
  h.point_format = format;
  h.scale[0] = 0.01, h.scale[1] = 0.001, h.scale[2] = 0.0025;
  h.offset[0] = 85000, h.offset[1] = 447000, h.offset[2] = -10;
  return h;
}

std::vector<hf::LasPoint> read_all(const std::string& bytes, const std::string& name, hf::LasHeader* header = nullptr,
                                   size_t chunk = 7) {
  std::istringstream in(bytes);
  hf::LasReader reader(in, bytes.size(), name);
  std::vector<hf::LasPoint> all, part;
  while (reader.read_chunk(part, chunk)) all.insert(all.end(), part.begin(), part.end());
  if (header) *header = reader.header();
  return all;
}

std::string error_of(const std::string& bytes, const std::string& name = "bad.las") {
  try {
    read_all(bytes, name);
  } catch (const hf::Error& e) {
    return e.what();
  }
  return "";
}

void set_u32(std::string& b, size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + i] = static_cast<char>((v >> (8 * i)) & 0xff);
}

TEST(Las, EveryFormatAndVersionRoundTrips) {
  for (int minor = 0; minor <= 4; ++minor)
    for (int format = 0; format <= 10; ++format) {
      if (format >= 6 && minor < 4) continue;
      if (format >= 4 && format <= 5 && minor < 3) continue;  // waveform formats arrived with LAS 1.3
      SCOPED_TRACE("LAS 1." + std::to_string(minor) + " format " + std::to_string(format));
      hf::LasHeader h = header_for(minor, format);
      h.vlrs.push_back({"LASF_Projection", 2112, "OGC WKT", {'W', 'K', 'T', 0}});
      const auto pts = random_points(format, 41, 100 + format * 7 + minor, h);
      const std::string bytes = hf::format_las(h, pts, "mem.las");
      EXPECT_EQ(bytes.size(), size_t(hf::las_header_size(minor)) + 54 + 4 + pts.size() * size_t(hf::las_min_record_length(format)));
      hf::LasHeader got;
      const auto back = read_all(bytes, "mem.las", &got);
      ASSERT_EQ(back.size(), pts.size());
      EXPECT_EQ(got.point_format, format);
      EXPECT_EQ(got.version_minor, minor);
      ASSERT_EQ(got.vlrs.size(), 1u);
      EXPECT_EQ(got.vlrs[0].user_id, "LASF_Projection");
      EXPECT_EQ(got.vlrs[0].record_id, 2112);
      EXPECT_EQ(got.vlrs[0].data.size(), 4u);
      for (size_t i = 0; i < pts.size(); ++i) {
        const auto &a = pts[i], &b = back[i];
        // One unit of the scale is the format's resolution; the round trip is exact up to double rounding.
        EXPECT_NEAR(a.x, b.x, 1e-6);
        EXPECT_NEAR(a.y, b.y, 1e-6);
        EXPECT_NEAR(a.z, b.z, 1e-6);
        EXPECT_EQ(a.intensity, b.intensity);
        EXPECT_EQ(a.return_number, b.return_number);
        EXPECT_EQ(a.number_of_returns, b.number_of_returns);
        EXPECT_EQ(a.classification, b.classification);
        EXPECT_EQ(a.synthetic, b.synthetic);
        EXPECT_EQ(a.key_point, b.key_point);
        EXPECT_EQ(a.withheld, b.withheld);
        EXPECT_EQ(a.overlap, b.overlap);
        EXPECT_EQ(a.scanner_channel, b.scanner_channel);
        EXPECT_NEAR(a.scan_angle_deg, b.scan_angle_deg, format >= 6 ? 0.0031 : 0.0);
        EXPECT_EQ(a.user_data, b.user_data);
        EXPECT_EQ(a.point_source_id, b.point_source_id);
        EXPECT_EQ(a.gps_time, b.gps_time);
        EXPECT_EQ(a.red, b.red);
        EXPECT_EQ(a.green, b.green);
        EXPECT_EQ(a.blue, b.blue);
        EXPECT_EQ(a.nir, b.nir);
      }
    }
}

TEST(Las, ExtendedClassificationUsesAllEightBits) {
  hf::LasHeader h = header_for(4, 6);
  std::vector<hf::LasPoint> pts(3);
  pts[0].classification = 6, pts[1].classification = 64, pts[2].classification = 255;
  const auto back = read_all(hf::format_las(h, pts, "m.las"), "m.las");
  EXPECT_EQ(back[1].classification, 64);
  EXPECT_EQ(back[2].classification, 255);
  // Formats 0-5 have 5 bits: class 6 + the synthetic flag in bit 5 must not leak into the class.
  h = header_for(2, 1);
  pts.assign(1, {});
  pts[0].classification = 6, pts[0].synthetic = true;
  const auto legacy = read_all(hf::format_las(h, pts, "m.las"), "m.las");
  EXPECT_EQ(legacy[0].classification, 6);
  EXPECT_TRUE(legacy[0].synthetic);
}

TEST(Las, ScaleAndOffsetApply) {
  hf::LasHeader h = header_for(2, 0);
  h.scale[0] = 0.5, h.offset[0] = 1000;
  std::vector<hf::LasPoint> pts(1);
  pts[0].x = 1003.5;  // integer 7
  std::string bytes = hf::format_las(h, pts, "m.las");
  const int x_raw = static_cast<unsigned char>(bytes[227]) | (static_cast<unsigned char>(bytes[228]) << 8);
  EXPECT_EQ(x_raw, 7);
  EXPECT_DOUBLE_EQ(read_all(bytes, "m.las")[0].x, 1003.5);
}

TEST(Las, EpsgFromTheGeoKeyDirectory) {
  hf::LasHeader h = header_for(2, 1);
  EXPECT_EQ(hf::las_epsg(h), 0);
  // Version 1.1.0, 2 keys: GTModelType = projected, ProjectedCSType = 28992 (Amersfoort / RD New).
  const std::uint16_t keys[] = {1, 1, 0, 2, 1024, 0, 1, 1, 3072, 0, 1, 28992};
  std::vector<std::uint8_t> data;
  for (std::uint16_t k : keys) data.push_back(static_cast<std::uint8_t>(k & 0xff)), data.push_back(static_cast<std::uint8_t>(k >> 8));
  h.vlrs.push_back({"LASF_Projection", 34735, "GeoKeyDirectoryTag", data});
  hf::LasHeader got;
  read_all(hf::format_las(h, {}, "m.las"), "m.las", &got);
  EXPECT_EQ(hf::las_epsg(got), 28992);
}

TEST(Las, LongerRecordsSkipTheirExtraBytes) {
  hf::LasHeader h = header_for(2, 1);
  h.record_length = 40;  // 12 extra bytes per record
  const auto pts = random_points(1, 9, 3, h);
  const std::string bytes = hf::format_las(h, pts, "m.las");
  hf::LasHeader got;
  const auto back = read_all(bytes, "m.las", &got);
  EXPECT_EQ(got.record_length, 40);
  ASSERT_EQ(back.size(), 9u);
  EXPECT_NEAR(back[8].z, pts[8].z, 1e-6);
  EXPECT_EQ(back[8].gps_time, pts[8].gps_time);
}

TEST(Las, MalformedInputNamesFileAndByte) {
  hf::LasHeader h = header_for(2, 3);
  const auto pts = random_points(3, 10, 5, h);
  const std::string good = hf::format_las(h, pts, "m.las");

  EXPECT_NE(error_of("").find("bad.las: byte 0: "), std::string::npos);
  std::string b = good;
  b[0] = 'X';
  EXPECT_NE(error_of(b).find("bad.las: byte 0: not a LAS file"), std::string::npos);
  EXPECT_NE(error_of(good.substr(0, 100)).find("bad.las: byte 100: header truncated"), std::string::npos);
  b = good, b[25] = 7;
  EXPECT_NE(error_of(b).find("byte 24: unsupported LAS version 1.7"), std::string::npos);
  b = good, b[104] = 11;
  EXPECT_NE(error_of(b).find("byte 104: unsupported point data format 11"), std::string::npos);
  b = good, b[105] = 20, b[106] = 0;
  EXPECT_NE(error_of(b).find("byte 105: point record length 20 below the 34 bytes of format 3"), std::string::npos);
  b = good, b[94] = 100, b[95] = 0;
  EXPECT_NE(error_of(b).find("byte 94: header size 100"), std::string::npos);
  b = good, set_u32(b, 96, 1u << 30);
  EXPECT_NE(error_of(b).find("byte 96: point data offset"), std::string::npos);
  b = good, std::memset(&b[131], 0, 8);
  EXPECT_NE(error_of(b).find("byte 131: x scale factor 0 outside 1e-09..10"), std::string::npos);
  b = good, set_u32(b, 100, 3);  // three VLRs that are not there
  EXPECT_NE(error_of(b).find("byte 227: VLR 1 of 3 runs into the point data"), std::string::npos);

  // A point count that lies: 11 promised, 10 present. Caught before reading, at the 11th record's offset.
  b = good, set_u32(b, 107, 11);
  EXPECT_NE(error_of(b).find("bad.las: byte " + std::to_string(227 + 10 * 34) + ": point record 11 of 11 truncated"),
            std::string::npos);
  // A truncated file: the last record is cut in half.
  EXPECT_NE(error_of(good.substr(0, good.size() - 17)).find("byte " + std::to_string(227 + 9 * 34) + ": point record 10 of 10"),
            std::string::npos);
  // A huge count cannot overflow the size check.
  b = good, set_u32(b, 107, 0xffffffffu);
  EXPECT_NE(error_of(b).find("of 4294967295 truncated"), std::string::npos);
}

TEST(Las, LazIsDetectedWithOneLine) {
  hf::LasHeader h = header_for(2, 1);
  std::string b = hf::format_las(h, random_points(1, 3, 1, h), "m.las");
  b[104] = static_cast<char>(1 | 0x80);  // LASzip sets bit 7 of the point format
  const std::string e = error_of(b, "tile.laz");
  EXPECT_NE(e.find("tile.laz: LAZ-compressed point data; decompress it first"), std::string::npos);
  EXPECT_EQ(e.find('\n'), std::string::npos);
  // The LASzip VLR alone also marks it.
  h.vlrs.push_back({"laszip encoded", 22204, "", {1, 2}});
  EXPECT_NE(error_of(hf::format_las(h, {}, "m.las"), "v.las").find("v.las: LAZ-compressed"), std::string::npos);
}

TEST(Las, FileRoundTripAndMissingFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_las_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "cloud.las").string();
  hf::LasHeader h = header_for(4, 7);
  const auto pts = random_points(7, 1000, 9, h);
  hf::write_las(path, h, pts);
  hf::LasReader reader(path);
  EXPECT_EQ(reader.header().point_count, 1000u);
  std::vector<hf::LasPoint> chunk;
  size_t n = 0, chunks = 0;
  while (reader.read_chunk(chunk, 300)) n += chunk.size(), ++chunks;
  EXPECT_EQ(n, 1000u);
  EXPECT_EQ(chunks, 4u);  // 300 + 300 + 300 + 100: streaming in bounded chunks
  std::filesystem::remove_all(dir);
  try {
    hf::LasReader missing((dir / "none.las").string());
    FAIL() << "no error for a missing file";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("none.las: cannot read LAS file (No such file"), std::string::npos);
  }
}

// Issue 35: a FIFO given as a LAS file blocked the ifstream's open forever; it is refused before opening.
TEST(Las, FifoIsRefusedBeforeOpening) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_las_fifo_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string fifo = (dir / "f.las").string();
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::string message;
  try {
    hf::LasReader reader(fifo);
  } catch (const hf::Error& e) {
    message = e.what();
  }
  std::filesystem::remove_all(dir);
  EXPECT_EQ(message, fifo + ": cannot read LAS file: it is a FIFO, not a regular file");
}

// Real files: their header facts from PROVENANCE.md, and the class counts re-counted there.
TEST(Las, SharedPdalSampleC) {
  const std::string path = std::string(HF_SHARED_DIR) + "/data/lidar_pdal_sample_c/sample_c.las";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " absent";
  hf::LasHeader h;
  const auto pts = hf::read_las(path, &h);
  EXPECT_EQ(h.version_minor, 2);
  EXPECT_EQ(h.point_format, 3);
  ASSERT_EQ(pts.size(), 14408u);
  std::map<int, int> classes;
  for (const auto& p : pts) {
    ++classes[p.classification];
    EXPECT_GE(p.x, h.min[0] - 0.01);
    EXPECT_LE(p.x, h.max[0] + 0.01);
    EXPECT_GE(p.z, 627.52);
    EXPECT_LE(p.z, 656.24);
  }
  EXPECT_EQ(classes[6], 12525);
  EXPECT_EQ(classes[2], 1368);
  EXPECT_EQ(classes[31], 339);
}

TEST(Las, SharedAhn3Delft) {
  const std::string dir = std::string(HF_SHARED_DIR) + "/data/lidar_ahn3_delft";
  if (!std::filesystem::exists(dir + "/ahn3_cropped_2.las")) GTEST_SKIP() << dir << " absent";
  hf::LasReader reader(dir + "/ahn3_cropped_2.las");
  EXPECT_EQ(reader.header().point_format, 1);
  EXPECT_EQ(reader.header().point_count, 208432u);
  std::map<int, int> classes;
  std::vector<hf::LasPoint> chunk;
  while (reader.read_chunk(chunk, 50000))
    for (const auto& p : chunk) ++classes[p.classification];
  EXPECT_EQ(classes[1], 86308);
  EXPECT_EQ(classes[2], 87130);
  EXPECT_EQ(classes[6], 33312);
  EXPECT_EQ(classes[9], 568);
  EXPECT_EQ(classes[26], 1114);
  try {
    hf::LasReader laz(dir + "/ahn3_cropped_1.laz");
    FAIL() << "LAZ read without an error";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("ahn3_cropped_1.laz: LAZ-compressed point data; decompress it first"), std::string::npos);
  }
}

}  // namespace
