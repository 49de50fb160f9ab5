#include "io/pcd.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <bit>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

#include "core/error.h"

namespace hf {
namespace {

namespace fs = std::filesystem;

std::string pcd_temp_path(const std::string& name) {
  return (fs::temp_directory_path() / ("hf_test_pcd_" + std::to_string(::getpid()) + "_" + name)).string();
}

bool pcd_same_bits(const std::vector<Eigen::Vector3f>& a, const std::vector<Eigen::Vector3f>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i)
    for (int k = 0; k < 3; ++k)
      if (std::bit_cast<std::uint32_t>(a[i][k]) != std::bit_cast<std::uint32_t>(b[i][k])) return false;
  return true;
}

class PcdRoundTrip : public ::testing::TestWithParam<std::tuple<bool, bool>> {};

TEST_P(PcdRoundTrip, IsBitExactAndKeepsOnlyTheAttributesWritten) {
  const auto [normals, colors] = GetParam();
  PointCloud c;
  for (int i = 0; i < 100; ++i) {
    const float t = static_cast<float>(i);
    c.positions.emplace_back(t / 3.0f, -t * 1e-7f, 1e20f / (t + 1.0f));
    if (normals) c.normals.emplace_back(Eigen::Vector3f(1.0f / 3.0f, t / 7.0f, -0.3f).normalized());
    if (colors) c.colors.push_back(Rgb8{std::uint8_t(i * 37), std::uint8_t(255 - i), std::uint8_t(i * 101 + 3)});
  }
  const std::string path = pcd_temp_path("rt.pcd");
  write_pcd(path, c);
  const PointCloud back = read_pcd(path);
  EXPECT_TRUE(pcd_same_bits(c.positions, back.positions));
  EXPECT_TRUE(pcd_same_bits(c.normals, back.normals));
  EXPECT_EQ(c.colors, back.colors);
  std::ifstream in(path);
  std::string header((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  EXPECT_NE(header.find("DATA binary\n"), std::string::npos);
  fs::remove(path);
}

INSTANTIATE_TEST_SUITE_P(AllCombinations, PcdRoundTrip, ::testing::Combine(::testing::Bool(), ::testing::Bool()));

TEST(Pcd, EmptyCloudRoundTrips) {
  const std::string path = pcd_temp_path("empty.pcd");
  write_pcd(path, PointCloud{});
  EXPECT_EQ(read_pcd(path).size(), 0u);
  fs::remove(path);
}

TEST(Pcd, AsciiFileWithNanPointsDropsThem) {
  const std::string path = pcd_temp_path("nan.pcd");
  std::ofstream(path) << "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\n"
                         "WIDTH 3\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 3\nDATA ascii\n"
                         "1 2 3 16711680\nnan nan nan 0\n4 5 6 255\n";
  const PointCloud c = read_pcd(path);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c.positions[1], Eigen::Vector3f(4, 5, 6));
  EXPECT_FALSE(c.has_normals());
  ASSERT_TRUE(c.has_colors());
  EXPECT_EQ(c.colors[0], (Rgb8{255, 0, 0}));
  EXPECT_EQ(c.colors[1], (Rgb8{0, 0, 255}));
  fs::remove(path);
}

TEST(Pcd, ErrorsNameTheFile) {
  const std::string missing = pcd_temp_path("missing.pcd");
  try {
    read_pcd(missing);
    FAIL();
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()), missing + ": cannot read PCD file (No such file or directory)");
  }
  const std::string garbage = pcd_temp_path("garbage.pcd");
  const std::string head = "VERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\nHEIGHT 1\n";
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"this is not a point cloud\n", ":1: expected a PCD header keyword"},
      {"", ":1: expected a 'DATA ascii|binary|binary_compressed' line"},
      {head + "POINTS 3\nDATA text\n", ":9: expected 'DATA ascii|binary|binary_compressed', got 'text'"},
      {"FIELDS x y z\nSIZE 4 4\nTYPE F F F\nPOINTS 0\nDATA ascii\n", ":2: expected 3 entries on the SIZE line"},
      {"FIELDS x y z\nSIZE 4 4 8\nTYPE F F F\nPOINTS 0\nDATA ascii\n", ":3: expected field 'z' to be one float"},
      {head + "POINTS 3\nDATA binary\n" + std::string(20, '\0'), ":8: expected 3 points of 12 bytes, got only 20 bytes"},
      {head + "POINTS 1099511627776\nDATA ascii\n1 2 3\n", ":8: expected 1099511627776 lines of points"},
  };
  for (const auto& [text, expected] : cases) {
    std::ofstream(garbage, std::ios::binary) << text;
    try {
      read_pcd(garbage);
      ADD_FAILURE() << "accepted: " << text;
    } catch (const ParseError& e) {
      EXPECT_NE(std::string(e.what()).find(garbage + expected), std::string::npos) << e.what();
    }
  }
  fs::remove(garbage);
  PointCloud bad;
  bad.positions = {{0, 0, 0}};
  bad.colors = {{1, 2, 3}, {4, 5, 6}};
  const std::string out = pcd_temp_path("bad.pcd");
  EXPECT_THROW(write_pcd(out, bad), Error);
  EXPECT_FALSE(fs::exists(out));
}

}  // namespace
}  // namespace hf
