#include "io/ply.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <tuple>
#include <utility>

#include "core/error.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

std::string ply_temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("hf_test_ply_" + std::to_string(::getpid()) + "_" + name)).string();
}

std::string ply_slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

void put(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

// Floats that expose lossy formatting: thirds, denormals, extremes, signed zero, values with long decimal forms.
float awkward(int i) {
  static const float kValues[] = {1.0f / 3.0f, -2.0f / 7.0f, 1e-40f, -0.0f, 3.4028235e38f, -1.17549435e-38f,
                                  0.1f,        123456.789f,  -7.5e-8f, 16777217.0f, 2.5f, 6.02214076e23f};
  const float base = kValues[static_cast<size_t>(i) % (sizeof(kValues) / sizeof(kValues[0]))];
  return i < 12 ? base : base * (1.0f - static_cast<float>(i % 37) * 0.011f);  // stays finite
}

TriangleMesh ply_make_mesh(bool normals, bool colors, bool faces, int n = 40) {
  TriangleMesh m;
  for (int i = 0; i < n; ++i) {
    m.vertices.emplace_back(awkward(3 * i), awkward(3 * i + 1), awkward(3 * i + 2));
    if (normals) m.normals.emplace_back(Eigen::Vector3f(awkward(i + 5), awkward(i + 7), 0.25f).normalized());
    if (colors) m.colors.push_back(Rgb8{std::uint8_t(i * 37), std::uint8_t(255 - i), std::uint8_t(i * 101 + 3)});
  }
  if (faces)
    for (int i = 0; i + 2 < n; ++i) m.triangles.emplace_back(i, (i * 7 + 1) % n, n - 1 - i);
  return m;
}

bool ply_same_bits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (std::bit_cast<std::uint32_t>(a[i][k]) != std::bit_cast<std::uint32_t>(b[i][k])) return false;
  return true;
}

void expect_identical(const TriangleMesh& a, const TriangleMesh& b) {
  EXPECT_TRUE(ply_same_bits(a.vertices, b.vertices));
  EXPECT_TRUE(ply_same_bits(a.normals, b.normals));
  EXPECT_EQ(a.colors, b.colors);
  EXPECT_EQ(a.triangles, b.triangles);
}

// ---------------------------------------------------------------------------------------------------------------
// Round trips: every format x normals x colours x faces, bit-exact.

using RoundTripParam = std::tuple<PlyFormat, bool, bool, bool>;
class PlyRoundTrip : public ::testing::TestWithParam<RoundTripParam> {};

TEST_P(PlyRoundTrip, MeshIsBitExact) {
  const auto [format, normals, colors, faces] = GetParam();
  const TriangleMesh mesh = ply_make_mesh(normals, colors, faces);
  const std::string path = ply_temp_path("roundtrip.ply");
  write_ply(path, mesh, {format, "line one\nline two"});
  const TriangleMesh back = read_ply_mesh(path);
  expect_identical(mesh, back);
  // The string form is exactly what was written.
  EXPECT_EQ(ply_slurp(path), format_ply(mesh, {format, "line one\nline two"}));
  fs::remove(path);
}

using CloudParam = std::tuple<PlyFormat, bool, bool>;
class PlyCloudRoundTrip : public ::testing::TestWithParam<CloudParam> {};

TEST_P(PlyCloudRoundTrip, IsBitExact) {
  const auto [format, normals, colors] = GetParam();
  const TriangleMesh m = ply_make_mesh(normals, colors, false);
  PointCloud cloud{m.vertices, m.normals, m.colors};
  const std::string path = ply_temp_path("cloud.ply");
  write_ply(path, cloud, {format, ""});
  const PointCloud back = read_ply_point_cloud(path);
  EXPECT_TRUE(ply_same_bits(cloud.positions, back.positions));
  EXPECT_TRUE(ply_same_bits(cloud.normals, back.normals));
  EXPECT_EQ(cloud.colors, back.colors);
  EXPECT_EQ(ply_slurp(path).find("element face"), std::string::npos);
  fs::remove(path);
}

INSTANTIATE_TEST_SUITE_P(AllCombinations, PlyRoundTrip,
                         ::testing::Combine(::testing::Values(PlyFormat::binary_little_endian,
                                                              PlyFormat::binary_big_endian, PlyFormat::ascii),
                                            ::testing::Bool(), ::testing::Bool(), ::testing::Bool()));
INSTANTIATE_TEST_SUITE_P(AllCombinations, PlyCloudRoundTrip,
                         ::testing::Combine(::testing::Values(PlyFormat::binary_little_endian,
                                                              PlyFormat::binary_big_endian, PlyFormat::ascii),
                                            ::testing::Bool(), ::testing::Bool()));

TEST(PlyWrite, DefaultIsBinaryLittleEndianWithDocumentedLayout) {
  const TriangleMesh mesh = ply_make_mesh(true, true, true, 4);
  const std::string bytes = format_ply(mesh);
  const std::string header =
      "ply\nformat binary_little_endian 1.0\ncomment written by hashfusion\nelement vertex 4\n"
      "property float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\nproperty float nz\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nelement face 2\n"
      "property list uchar int vertex_indices\nend_header\n";
  ASSERT_EQ(bytes.substr(0, header.size()), header);
  // 4 vertices x (6 floats + 3 bytes) + 2 faces x (1 + 3 x 4 bytes).
  EXPECT_EQ(bytes.size(), header.size() + 4 * 27 + 2 * 13);
  float x0 = 0;
  std::memcpy(&x0, bytes.data() + header.size(), 4);
  EXPECT_EQ(std::bit_cast<std::uint32_t>(x0), std::bit_cast<std::uint32_t>(mesh.vertices[0].x()));
}

TEST(PlyWrite, EmptyMeshRoundTrips) {
  for (PlyFormat f : {PlyFormat::binary_little_endian, PlyFormat::ascii}) {
    const TriangleMesh back = parse_ply_mesh(format_ply(TriangleMesh{}, {f, ""}), "empty.ply");
    EXPECT_TRUE(back.vertices.empty());
    EXPECT_TRUE(back.triangles.empty());
  }
}

TEST(PlyWrite, InvalidMeshIsRefusedAndExistingFileKept) {
  const std::string path = ply_temp_path("keep.ply");
  put(path, "previous contents");
  TriangleMesh bad = ply_make_mesh(false, false, true, 5);
  bad.triangles.emplace_back(0, 1, 5);
  try {
    write_ply(path, bad);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("triangle 3 index 5 is outside [0, 5)"), std::string::npos) << e.what();
  }
  TriangleMesh nan_mesh = ply_make_mesh(false, false, false, 3);
  nan_mesh.vertices[1].y() = std::nanf("");
  EXPECT_THROW(write_ply(path, nan_mesh), Error);
  TriangleMesh short_normals = ply_make_mesh(true, false, false, 3);
  short_normals.normals.pop_back();
  EXPECT_THROW(write_ply(path, short_normals), Error);
  EXPECT_EQ(ply_slurp(path), "previous contents");
  fs::remove(path);
}

TEST(PlyWrite, UnwritableFolderThrowsNamingThePath) {
  const std::string path = ply_temp_path("no_such_folder") + "/out.ply";
  try {
    write_ply(path, ply_make_mesh(false, false, true, 3));
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Files written by hand: extra properties of every type, lists, aliases, float colours, polygons, other elements.

TEST(PlyRead, AsciiWithExtraPropertiesAndTypes) {
  const std::string text =
      "ply\r\n"
      "format ascii 1.0\r\n"
      "comment hand written, CRLF line ends\r\n"
      "obj_info anything\r\n"
      "element vertex 4\r\n"
      "property double x\r\n"
      "property int8 flags\r\n"
      "property float32 y\r\n"
      "property list uchar float texcoord\r\n"
      "property float z\r\n"
      "property uint16 id\r\n"
      "property float nx\r\n"
      "property float ny\r\n"
      "property float nz\r\n"
      "property float red\r\n"
      "property float green\r\n"
      "property float blue\r\n"
      "property float alpha\r\n"
      "element face 2\r\n"
      "property uchar intensity\r\n"
      "property list int uint vertex_index\r\n"
      "property float64 quality\r\n"
      "element edge 1\r\n"
      "property int vertex1\r\n"
      "property int vertex2\r\n"
      "end_header\r\n"
      "0.5 -3 1.25 2 0.1 0.2 -1 65535 0 0 1 1 0 0.5 1\r\n"
      "1 127 2 0 3 7 1 0 0 0 0 0 0\r\n"
      "\r\n"
      "  -1e2\t0 -0 3 1 2 3 4.5e-1 0 0 0 1 0.2 0.4 0.6 0.8\r\n"
      "2 -128 4 1 9 5 6 0 -1 0 1 1 1 1\r\n"
      "255 4 0 1 2 3 1e300\r\n"
      "0 3 3 2 1 -0.5\r\n"
      "0 1\r\n";
  const TriangleMesh m = parse_ply_mesh(text, "hand.ply");
  ASSERT_EQ(m.vertices.size(), 4u);
  EXPECT_EQ(m.vertices[0], Eigen::Vector3f(0.5f, 1.25f, -1.0f));
  EXPECT_EQ(m.vertices[1], Eigen::Vector3f(1.0f, 2.0f, 3.0f));
  EXPECT_EQ(m.vertices[2], Eigen::Vector3f(-100.0f, -0.0f, 0.45f));
  EXPECT_EQ(m.vertices[3], Eigen::Vector3f(2.0f, 4.0f, 5.0f));
  ASSERT_EQ(m.normals.size(), 4u);
  EXPECT_EQ(m.normals[0], Eigen::Vector3f(0, 0, 1));
  EXPECT_EQ(m.normals[3], Eigen::Vector3f(0, -1, 0));
  ASSERT_EQ(m.colors.size(), 4u);
  EXPECT_EQ(m.colors[0], (Rgb8{255, 0, 128}));  // float colours in [0, 1]; 0.5 * 255 = 127.5 rounds up
  EXPECT_EQ(m.colors[1], (Rgb8{0, 0, 0}));
  EXPECT_EQ(m.colors[2], (Rgb8{51, 102, 153}));
  EXPECT_EQ(m.colors[3], (Rgb8{255, 255, 255}));
  // The quad 0 1 2 3 is fanned into (0 1 2) (0 2 3); the triangle follows.
  ASSERT_EQ(m.triangles.size(), 3u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(0, 2, 3));
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(3, 2, 1));
}

// Appends a scalar in the requested byte order.
template <class T>
void append(std::string& s, T v, bool big) {
  char b[sizeof(T)];
  std::memcpy(b, &v, sizeof(T));
  if (big) std::reverse(b, b + sizeof(T));
  s.append(b, sizeof(T));
}

std::string binary_with_every_type(bool big) {
  std::string s = std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\n"
                  "element vertex 2\n"
                  "property char a\nproperty float x\nproperty uchar b\nproperty double y\nproperty short c\n"
                  "property ushort d\nproperty float z\nproperty int e\nproperty uint f\n"
                  "property list ushort double g\nproperty uint8 red\nproperty uint8 green\nproperty uint8 blue\n"
                  "property uint8 alpha\n"
                  "element face 1\n"
                  "property list uint8 int32 vertex_indices\n"
                  "property list int int8 other\n"
                  "end_header\n";
  for (int i = 0; i < 2; ++i) {
    append<std::int8_t>(s, -5, big);
    append<float>(s, 1.5f + static_cast<float>(i), big);
    append<std::uint8_t>(s, 250, big);
    append<double>(s, -2.25 * (i + 1), big);
    append<std::int16_t>(s, -30000, big);
    append<std::uint16_t>(s, 60000, big);
    append<float>(s, 1e-3f, big);
    append<std::int32_t>(s, -7, big);
    append<std::uint32_t>(s, 4000000000u, big);
    append<std::uint16_t>(s, static_cast<std::uint16_t>(i + 1), big);
    for (int k = 0; k <= i; ++k) append<double>(s, 99.0, big);
    for (std::uint8_t c : {std::uint8_t(10 + i), std::uint8_t(20 + i), std::uint8_t(30 + i), std::uint8_t(40)})
      append<std::uint8_t>(s, c, big);
  }
  append<std::uint8_t>(s, 3, big);
  for (int v : {1, 0, 1}) append<std::int32_t>(s, v, big);
  append<std::int32_t>(s, 2, big);
  append<std::int8_t>(s, -1, big);
  append<std::int8_t>(s, 1, big);
  return s;
}

TEST(PlyRead, BinaryWithEveryScalarTypeBothEndiannesses) {
  for (bool big : {false, true}) {
    SCOPED_TRACE(big ? "big endian" : "little endian");
    const TriangleMesh m = parse_ply_mesh(binary_with_every_type(big), "types.ply");
    ASSERT_EQ(m.vertices.size(), 2u);
    EXPECT_EQ(m.vertices[0], Eigen::Vector3f(1.5f, -2.25f, 1e-3f));
    EXPECT_EQ(m.vertices[1], Eigen::Vector3f(2.5f, -4.5f, 1e-3f));
    EXPECT_TRUE(m.normals.empty());
    ASSERT_EQ(m.colors.size(), 2u);
    EXPECT_EQ(m.colors[1], (Rgb8{11, 21, 31}));
    ASSERT_EQ(m.triangles.size(), 1u);
    EXPECT_EQ(m.triangles[0], Eigen::Vector3i(1, 0, 1));
  }
}

TEST(PlyRead, TristripsAlternateWindingRestartAndDropDegenerates) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 7\nproperty float x\nproperty float y\nproperty float z\n"
      "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 2 0\n1 2 0\n0.5 1 0\n"
      "11 0 1 2 3 4 4 -1 5 4 6 6\n";
  const TriangleMesh m = parse_ply_mesh(text, "strips.ply");
  // Strip 0 1 2 3 4 4: (0 1 2) (2 1 3) (2 3 4), then (4 3 4) is degenerate; after the -1 restart: (5 4 6), then
  // (6 4 6) is degenerate.
  ASSERT_EQ(m.triangles.size(), 4u);
  EXPECT_EQ(m.triangles[0], Eigen::Vector3i(0, 1, 2));
  EXPECT_EQ(m.triangles[1], Eigen::Vector3i(2, 1, 3));
  EXPECT_EQ(m.triangles[2], Eigen::Vector3i(2, 3, 4));
  EXPECT_EQ(m.triangles[3], Eigen::Vector3i(5, 4, 6));
  // Consistent orientation: all four face +z, so the signed areas agree.
  for (const Eigen::Vector3i& t : m.triangles) {
    const Eigen::Vector3f n = (m.vertices[t[1]] - m.vertices[t[0]]).cross(m.vertices[t[2]] - m.vertices[t[0]]);
    EXPECT_GT(n.z(), 0) << t.transpose();
  }
}

TEST(PlyRead, IntegerColoursOfOtherWidthsAndNoFaceElement) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
      "property ushort r\nproperty ushort g\nproperty ushort b\nend_header\n"
      "1 2 3 65535 0 32768\n4 5 6 257 514 771\n";
  const TriangleMesh m = parse_ply_mesh(text, "c16.ply");
  ASSERT_EQ(m.colors.size(), 2u);
  EXPECT_EQ(m.colors[0], (Rgb8{255, 0, 128}));
  EXPECT_EQ(m.colors[1], (Rgb8{1, 2, 3}));
  EXPECT_TRUE(m.triangles.empty());
}

TEST(PlyRead, PointCloudReaderStillChecksFaces) {
  const std::string text =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n3 0 0 1\n";
  EXPECT_THROW(parse_ply_point_cloud(text, "cloud.ply"), ParseError);
}

TEST(PlyRead, ZeroCountElementsWithoutPropertiesCostNothing) {
  // An element with no properties takes no bytes, so any count is consistent; it must not be iterated.
  const std::string text =
      "ply\nformat binary_little_endian 1.0\nelement marker 1099511627776\nelement vertex 0\nproperty float x\n"
      "property float y\nproperty float z\nend_header\n";
  EXPECT_TRUE(parse_ply_mesh(text, "m.ply").vertices.empty());
}

// ---------------------------------------------------------------------------------------------------------------
// Malformed input: each case names the file, the line (or element index) and what was expected.

struct PlyBadCase {
  const char* what;
  std::string bytes;
  std::string expected;  // substring of what()
};

const std::string kXyz = "property float x\nproperty float y\nproperty float z\n";
const std::string kFace = "element face 1\nproperty list uchar int vertex_indices\n";

std::string le_body(std::initializer_list<float> values) {
  std::string s;
  for (float v : values) append<float>(s, v, false);
  return s;
}

std::vector<PlyBadCase> bad_cases() {
  const std::string ascii3 = "ply\nformat ascii 1.0\nelement vertex 3\n" + kXyz;
  const std::string ascii1 = "ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz;
  const std::string bin_list2 = "ply\nformat binary_little_endian 1.0\nelement vertex 2\n" + kXyz + "property list uchar float extra\n";
  const std::string bin3 = "ply\nformat binary_little_endian 1.0\nelement vertex 3\n" + kXyz;
  return {
      {"empty", "", "bad.ply:1: expected 'ply' as the first line"},
      {"magic", "plx\nformat ascii 1.0\n", "bad.ply:1: expected 'ply' as the first line, got 'plx'"},
      {"binary junk magic", std::string("\x89PNG\r\n\x1a\n", 8), "bad.ply:1: expected 'ply'"},
      {"no end_header", "ply\nformat ascii 1.0\nelement vertex 0\n", "bad.ply:4: expected 'end_header'"},
      {"no format", "ply\nelement vertex 0\n" + kXyz + "end_header\n", "bad.ply:6: expected a 'format' line"},
      {"unknown format", "ply\nformat binary_middle_endian 1.0\n", "bad.ply:2: expected format ascii, binary_little_endian"},
      {"format version", "ply\nformat ascii 2.0\n", "bad.ply:2: expected 'format ascii|binary_little_endian"},
      {"bad type", "ply\nformat ascii 1.0\nelement vertex 1\nproperty flaot x\n",
       "bad.ply:4: expected a PLY scalar type (char uchar short ushort int uint float double), got 'flaot'"},
      {"float list count", "ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int v\n",
       "bad.ply:4: expected an integer list count type"},
      {"property first", "ply\nformat ascii 1.0\nproperty float x\n",
       "bad.ply:3: expected 'element' before the first 'property'"},
      {"bad count", "ply\nformat ascii 1.0\nelement vertex -3\n", "bad.ply:3: expected a non-negative element count, got '-3'"},
      {"unknown keyword", "ply\nformat ascii 1.0\nelemnt vertex 3\n", "bad.ply:3: expected 'format', 'element'"},
      {"duplicate property", "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n",
       "bad.ply:5: expected one property 'x' in element 'vertex'"},
      {"no vertex element", "ply\nformat ascii 1.0\nelement point 0\n" + kXyz + "end_header\n",
       "bad.ply:7: expected an element 'vertex'"},
      {"no z", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nend_header\n",
       "bad.ply:3: expected all or none of the properties x, y, z"},
      {"partial normals", "ply\nformat ascii 1.0\nelement vertex 0\n" + kXyz + "property float nx\nend_header\n",
       "bad.ply:3: expected all or none of the properties nx, ny, nz"},
      {"list coordinate", "ply\nformat ascii 1.0\nelement vertex 0\nproperty list uchar float x\nproperty float y\nproperty float z\nend_header\n",
       "bad.ply:3: expected property 'x' to be a scalar"},
      {"face without indices", "ply\nformat ascii 1.0\nelement vertex 0\n" + kXyz + "element face 0\nproperty uchar n\nend_header\n",
       "bad.ply:7: expected a list property 'vertex_indices' in element 'face'"},
      {"float indices", "ply\nformat ascii 1.0\nelement vertex 0\n" + kXyz + "element face 0\nproperty list uchar float vertex_indices\nend_header\n",
       "bad.ply:7: expected 'vertex_indices' to be a list of integers"},
      {"ascii too few values", ascii3 + "end_header\n0.0 0.0 0.0\n1.0 1.0\n2.0 2.0 2.0\n", "bad.ply:9: vertex 1: expected more values on the line"},
      {"ascii too many values", ascii1 + "end_header\n0 0 0 0\n", "bad.ply:8: vertex 0: expected the end of the line, got '0'"},
      {"ascii bad number", ascii1 + "end_header\n1 1x 1\n", "bad.ply:8: vertex 0: expected a float, got '1x'"},
      {"ascii nan", ascii3 + "end_header\n0 0 0\n1 1 1\nnan 0 0\n", "bad.ply:10: vertex 2: expected finite float coordinates"},
      {"ascii overflow to inf", ascii1 + "end_header\n1e39 0 0\n", "bad.ply:8: vertex 0: expected finite float coordinates"},
      {"ascii truncated", ascii3 + "end_header\n0.000 0.000 0.000\n1 1 1\n", "bad.ply:10: vertex 2: expected a line of values, got the end of the file"},
      {"ascii trailing garbage", ascii3 + "end_header\n0 0 0\n1 1 1\n2 2 2\n\nextra\n",
       "bad.ply:12: expected the end of the file after the last element, got 'extra'"},
      {"ascii index out of range", ascii3 + kFace + "end_header\n0 0 0\n1 1 1\n2 2 2\n3 0 1 3\n",
       "bad.ply:13: face 0: expected vertex indices in [0, 3), got 3"},
      {"ascii negative index", ascii3 + kFace + "end_header\n0 0 0\n1 1 1\n2 2 2\n3 0 -1 2\n",
       "bad.ply:13: face 0: expected vertex indices in [0, 3), got -1"},
      {"ascii uchar range", ascii3 + kFace + "end_header\n0 0 0\n1 1 1\n2 2 2\n300 0 1 2\n",
       "bad.ply:13: face 0: expected an integer of type uchar (0..255), got '300'"},
      {"ascii list longer than line", ascii3 + kFace + "end_header\n0 0 0\n1 1 1\n2 2 2\n200 0 1 2\n",
       "bad.ply:13: face 0: unexpected end of line in a list of 200 vertex indices"},
      {"ascii absurd count", "ply\nformat ascii 1.0\nelement vertex 1099511627776\n" + kXyz + "end_header\n0 0 0\n",
       "bad.ply:3: expected 1099511627776 'vertex' elements of at least 6 bytes each, got 6 bytes left in the file, "
       "room for 1 (truncated file?)"},
      {"ascii header only", "ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "end_header\n",
       "bad.ply:3: expected 1 'vertex' element after 'end_header', got the end of the file (truncated file?)"},
      {"binary truncated", bin_list2 + "end_header\n" + le_body({0, 0, 0}) + "\x05" + le_body({1, 2, 3, 4, 5}),
       "bad.ply: vertex 1: unexpected end of file"},
      {"binary truncated face", bin3 + kFace + "end_header\n" + le_body({0, 0, 0, 1, 1, 1, 2, 2, 2}) + "\x03" + std::string(8, '\0'),
       "bad.ply: face 0: unexpected end of file in a list of 3 vertex indices"},
      {"binary absurd count", "ply\nformat binary_little_endian 1.0\nelement vertex 1099511627776\n" + kXyz + "end_header\n" + le_body({0, 0, 0}),
       "bad.ply:3: expected 1099511627776 'vertex' elements of at least 12 bytes each, got 12 bytes left in the file"},
      {"binary nan", bin3 + "end_header\n" + le_body({0, 0, 0, 1, std::nanf(""), 1, 2, 2, 2}),
       "bad.ply: vertex 1: expected finite float coordinates"},
      {"binary index out of range", bin3 + kFace + "end_header\n" + le_body({0, 0, 0, 1, 1, 1, 2, 2, 2}) + "\x03" +
                                        std::string("\x00\x00\x00\x00\x01\x00\x00\x00\x07\x00\x00\x00", 12),
       "bad.ply: face 0: expected vertex indices in [0, 3), got 7"},
      {"binary huge list", bin3 + kFace + "end_header\n" + le_body({0, 0, 0, 1, 1, 1, 2, 2, 2}) + "\xff" + std::string(8, '\0'),
       "bad.ply: face 0: unexpected end of file in a list of 255 vertex indices"},
      {"binary negative list length",
       bin3 + "element face 1\nproperty list int int vertex_indices\nend_header\n" + le_body({0, 0, 0, 1, 1, 1, 2, 2, 2}) +
           std::string("\xff\xff\xff\xff", 4),
       "bad.ply: face 0: expected a non-negative list length for 'vertex_indices', got -1"},
      {"too many vertices for int indices",
       "ply\nformat binary_little_endian 1.0\nelement vertex 4294967296\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
       "bad.ply:3: expected at most 2^31-1 vertices, got 4294967296"},
  };
}

TEST(PlyRead, MalformedInputGivesOneClearParseError) {
  for (const PlyBadCase& c : bad_cases()) {
    SCOPED_TRACE(c.what);
    try {
      parse_ply_mesh(c.bytes, "bad.ply");
      ADD_FAILURE() << "expected hf::ParseError";
    } catch (const ParseError& e) {
      EXPECT_EQ(e.file(), "bad.ply");
      EXPECT_NE(std::string(e.what()).find(c.expected), std::string::npos)
          << "  message: " << e.what() << "\n  expected to contain: " << c.expected;
    }
  }
}

// 100,000 properties in one element: the duplicate-name check was a scan of the properties so far (11.6 s of
// comparisons before the body's size was even checked); now a set. The error is the body's, named at its element.
TEST(PlyRead, HeaderOfAHundredThousandPropertiesIsReadInOnePass) {
  std::string header = "ply\nformat ascii 1.0\nelement vertex 1\n";
  for (int i = 0; i < 100000; ++i) header += "property float p" + std::to_string(i) + "\n";
  header += "end_header\n";
  try {
    parse_ply_mesh(header, "wide.ply");
    FAIL() << "expected hf::ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()),
              "wide.ply:3: expected 1 'vertex' element after 'end_header', got the end of the file (truncated file?)");
  }
  try {
    parse_ply_mesh(header.substr(0, header.size() - 11) + "property float p99999\nend_header\n", "wide.ply");
    FAIL() << "expected hf::ParseError";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("wide.ply:100004: expected one property 'p99999' in element 'vertex'"),
              std::string::npos) << e.what();
  }
}

TEST(PlyRead, ErrorsFromFilesNameThePath) {
  const std::string path = ply_temp_path("broken.ply");
  put(path, "ply\nformat ascii 1.0\nelement vertex 1\n" + kXyz + "end_header\n0 zero 0\n");
  try {
    read_ply_mesh(path);
    FAIL() << "expected hf::ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()), path + ":8: vertex 0: expected a float, got 'zero'");
    EXPECT_EQ(e.line(), 8);
  }
  fs::remove(path);
  try {
    read_ply_mesh(path);
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), path + ": cannot read PLY file (No such file or directory)");
  }
}

TEST(PlyRead, EveryTruncationOfABinaryFileFailsCleanly) {
  const std::string full = format_ply(ply_make_mesh(true, true, true, 6));
  const size_t header_end = full.find("end_header\n") + 11;
  for (size_t n = 0; n < full.size(); ++n) {
    try {
      parse_ply_mesh(std::string_view(full).substr(0, n), "cut.ply");
      ADD_FAILURE() << "a file cut to " << n << " bytes was accepted";
    } catch (const ParseError& e) {
      const std::string msg = e.what();
      if (n >= header_end) {
        // Either the counts no longer fit the bytes left (caught before reading) or a face list runs out.
        EXPECT_TRUE(msg.find("(truncated file?)") != std::string::npos ||
                    msg.find("unexpected end of file") != std::string::npos)
            << msg;
      }
    }
  }
}

TEST(PlyRead, EveryTruncationOfAnAsciiFileFailsCleanly) {
  const std::string full = format_ply(ply_make_mesh(true, true, true, 6), {PlyFormat::ascii, ""});
  const size_t last_line = full.rfind('\n', full.size() - 2) + 1;
  for (size_t n = 0; n < full.size(); ++n) {
    try {
      parse_ply_mesh(std::string_view(full).substr(0, n), "cut.ply");
      // Only a cut inside the last line (the last face) can still be well formed, e.g. "3 0 1 12" -> "3 0 1 1".
      EXPECT_GE(n, last_line) << "a file cut to " << n << " bytes was accepted";
    } catch (const ParseError&) {
    }
  }
}

// ---------------------------------------------------------------------------------------------------------------
// Real data: the Igea head scan stores its surface as one triangle strip with restarts.

TEST(PlyRead, IgeaHeadTristrips) {
  const std::string path = std::string(HF_SHARED_DIR) + "/data/head_meshes/igea_tristrips.ply";
  if (!fs::exists(path)) GTEST_SKIP() << "real data not present: " << path;
  const TriangleMesh m = read_ply_mesh(path);
  EXPECT_EQ(m.vertices.size(), 134345u);
  // PROVENANCE.md: 268,686 strip triangles "may include degenerates"; none are (a closed surface of genus 0 has
  // 2V - 4 = 268,686 triangles).
  EXPECT_EQ(m.triangles.size(), 268686u);
  m.validate();
  Eigen::Vector3f lo = m.vertices[0], hi = m.vertices[0];
  for (const auto& v : m.vertices) {
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
  }
  const Eigen::Vector3f extent = hi - lo;  // ~0.069 x 0.099 x 0.099 m
  EXPECT_NEAR(extent.maxCoeff(), 0.099, 0.01);
  EXPECT_NEAR(extent.minCoeff(), 0.069, 0.01);
  // Alternating strip winding keeps the surface consistently oriented: an interior edge is used once in each
  // direction, never twice in the same direction.
  // Sorted directed edges (a << 32 | b): repeats and opposites are found by binary search.
  std::vector<std::uint64_t> edges;
  edges.reserve(m.triangles.size() * 3);
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      edges.push_back((static_cast<std::uint64_t>(t[k]) << 32) | static_cast<std::uint32_t>(t[(k + 1) % 3]));
  std::sort(edges.begin(), edges.end());
  size_t same_direction = 0, without_opposite = 0;
  for (size_t i = 0; i < edges.size(); ++i) {
    if (i > 0 && edges[i] == edges[i - 1]) ++same_direction;
    if (!std::binary_search(edges.begin(), edges.end(), (edges[i] << 32) | (edges[i] >> 32))) ++without_opposite;
  }
  std::cout << "igea: " << m.vertices.size() << " vertices, " << m.triangles.size() << " triangles, " << edges.size()
            << " directed edges, " << same_direction << " repeated in the same direction, " << without_opposite
            << " without their opposite\n";
  // Measured: 268,686 triangles, no repeats, every edge matched -- a closed, consistently oriented surface.
  EXPECT_EQ(same_direction, 0u);
  EXPECT_EQ(without_opposite, 0u);
  // And it survives our own writer bit-exactly, in both encodings.
  expect_identical(m, parse_ply_mesh(format_ply(m), "igea_copy.ply"));
}

}  // namespace
}  // namespace hf
