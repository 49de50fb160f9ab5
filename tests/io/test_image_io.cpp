// Image loading and writing: units, channel order, invalid values, failures, atomic writes.
#include "io/image_io.h"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "io/image_header.h"
#include "tests/io/test_dataset_util.h"

namespace fs = std::filesystem;

// The dataset tests' self-removing folder and error helper (one definition for every io test).
using hf::test::error_of;
using hf::test::TempDir;

TEST(ImageIo, DepthPngRoundTripWithinHalfAQuantum) {
  TempDir dir("depth_rt");
  hf::DepthImage depth(7, 5);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) depth(x, y) = 0.5f + 0.123457f * float(x + 7 * y);
  const std::string path = dir / "d.png";
  hf::write_depth_png(path, depth);
  const hf::DepthImage back = hf::load_depth(path);
  ASSERT_EQ(back.width(), 7);
  ASSERT_EQ(back.height(), 5);
  for (int y = 0; y < 5; ++y)
    for (int x = 0; x < 7; ++x) EXPECT_NEAR(back(x, y), depth(x, y), 0.5 / 5000.0 + 1e-6);
  // The file is 16-bit raw = round(d * 5000).
  const cv::Mat raw = cv::imread(path, cv::IMREAD_ANYDEPTH);
  ASSERT_EQ(raw.type(), CV_16UC1);
  EXPECT_EQ(raw.at<std::uint16_t>(0, 1), std::uint16_t(std::lround(depth(1, 0) * 5000.0)));
}

TEST(ImageIo, DepthWriteMapsInvalidAndOutOfRangeToZero) {
  TempDir dir("depth_invalid");
  hf::DepthImage depth(5, 1, 1.0f);
  depth(0, 0) = std::numeric_limits<float>::quiet_NaN();
  depth(1, 0) = std::numeric_limits<float>::infinity();
  depth(2, 0) = -2.0f;
  depth(3, 0) = 14.0f;  // 70000 raw units at 5000 per metre: beyond 16 bits
  const std::string path = dir / "d.png";
  hf::write_depth_png(path, depth);
  const hf::DepthImage back = hf::load_depth(path);
  for (int x = 0; x < 4; ++x) EXPECT_EQ(back(x, 0), 0.0f) << x;
  EXPECT_FLOAT_EQ(back(4, 0), 1.0f);
  // At scale 1000 (millimetres) 14 m fits.
  hf::write_depth_png(path, depth, 1000.0);
  EXPECT_FLOAT_EQ(hf::load_depth(path, {1000.0, -1})(3, 0), 14.0f);
}

TEST(ImageIo, Raw16ScaleAndExtraInvalidValue) {
  TempDir dir("raw16");
  cv::Mat raw(2, 3, CV_16UC1);
  raw.at<std::uint16_t>(0, 0) = 0;
  raw.at<std::uint16_t>(0, 1) = 801;
  raw.at<std::uint16_t>(0, 2) = 3493;
  raw.at<std::uint16_t>(1, 0) = 65535;
  raw.at<std::uint16_t>(1, 1) = 1000;
  raw.at<std::uint16_t>(1, 2) = 65534;
  const std::string path = dir / "mm.png";
  ASSERT_TRUE(cv::imwrite(path, raw));
  const hf::DepthImage d = hf::load_depth(path, {1000.0, 65535});
  EXPECT_EQ(d(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(d(1, 0), 0.801f);
  EXPECT_FLOAT_EQ(d(2, 0), 3.493f);
  EXPECT_EQ(d(0, 1), 0.0f);
  EXPECT_FLOAT_EQ(d(1, 1), 1.0f);
  EXPECT_FLOAT_EQ(d(2, 1), 65.534f);
  // Without the extra invalid value 65535 is a (far) depth.
  EXPECT_FLOAT_EQ(hf::load_depth(path, {1000.0, -1})(0, 1), 65.535f);
  EXPECT_FALSE(error_of([&] { hf::load_depth(path, {0.0, -1}); }).empty());
  EXPECT_FALSE(error_of([&] { hf::load_depth(path, {-5.0, -1}); }).empty());
}

TEST(ImageIo, FloatDepthRejectsNonFinite) {
  TempDir dir("float_depth");
  cv::Mat f(1, 5, CV_32FC1);
  f.at<float>(0, 0) = 1.25f;
  f.at<float>(0, 1) = std::numeric_limits<float>::quiet_NaN();
  f.at<float>(0, 2) = std::numeric_limits<float>::infinity();
  f.at<float>(0, 3) = -1.0f;
  f.at<float>(0, 4) = 0.0f;
  const std::string path = dir / "d.tiff";
  bool written = false;
  try {
    written = cv::imwrite(path, f);
  } catch (const cv::Exception&) {
  }
  if (!written) GTEST_SKIP() << "this OpenCV build cannot write 32-bit float TIFF";
  const hf::DepthImage d = hf::load_depth(path);
  EXPECT_FLOAT_EQ(d(0, 0), 1.25f);  // metres as stored; the 16-bit scale does not apply
  for (int x = 1; x < 5; ++x) EXPECT_EQ(d(x, 0), 0.0f) << x;
}

TEST(ImageIo, ColorIsRgbNotBgr) {
  TempDir dir("color");
  cv::Mat bgr(2, 2, CV_8UC3, cv::Scalar(255, 0, 0));  // pure blue in OpenCV's BGR order
  bgr.at<cv::Vec3b>(1, 1) = cv::Vec3b(10, 20, 30);
  const std::string path = dir / "c.png";
  ASSERT_TRUE(cv::imwrite(path, bgr));
  const hf::ColorImage c = hf::load_color(path);
  EXPECT_EQ(c(0, 0), (hf::Rgb8{0, 0, 255}));
  EXPECT_EQ(c(1, 1), (hf::Rgb8{30, 20, 10}));
}

TEST(ImageIo, ColorPngRoundTripIsExactAndJpegIsClose) {
  TempDir dir("color_rt");
  hf::ColorImage c(16, 16);
  for (int y = 0; y < 16; ++y)
    for (int x = 0; x < 16; ++x) c(x, y) = hf::Rgb8{std::uint8_t(x * 16), std::uint8_t(y * 16), 200};
  const std::string png = dir / "c.png";
  hf::write_color_png(png, c);
  EXPECT_EQ(hf::load_color(png).pixels(), c.pixels());

  // JPEG: a flat red image survives lossy coding within a few levels, in RGB order.
  cv::Mat red(16, 16, CV_8UC3, cv::Scalar(0, 0, 250));
  const std::string jpg = dir / "c.jpg";
  ASSERT_TRUE(cv::imwrite(jpg, red));
  const hf::ColorImage j = hf::load_color(jpg);
  EXPECT_NEAR(j(8, 8).r, 250, 6);
  EXPECT_NEAR(j(8, 8).g, 0, 6);
  EXPECT_NEAR(j(8, 8).b, 0, 6);
}

TEST(ImageIo, GreyColourImageIsExpanded) {
  TempDir dir("grey");
  cv::Mat grey(3, 3, CV_8UC1, cv::Scalar(77));
  ASSERT_TRUE(cv::imwrite(dir / "g.png", grey));
  EXPECT_EQ(hf::load_color(dir / "g.png")(2, 2), (hf::Rgb8{77, 77, 77}));
}

TEST(ImageIo, LoadFailuresNameTheFile) {
  TempDir dir("fail");
  const std::string missing = dir / "missing.png";
  EXPECT_NE(error_of([&] { hf::load_depth(missing); }).find(missing), std::string::npos);
  EXPECT_NE(error_of([&] { hf::load_color(missing); }).find(missing), std::string::npos);

  // Truncated PNG: first half of a valid file.
  hf::DepthImage depth(64, 64, 1.0f);
  const std::string full = dir / "full.png";
  hf::write_depth_png(full, depth);
  const std::string truncated = dir / "truncated.png";
  {
    std::ifstream in(full, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::ofstream out(truncated, std::ios::binary);
    out << bytes.substr(0, bytes.size() / 2);
  }
  EXPECT_NE(error_of([&] { hf::load_depth(truncated); }).find(truncated), std::string::npos);

  // Not an image at all.
  const std::string text = dir / "text.png";
  std::ofstream(text) << "not a png\n";
  EXPECT_NE(error_of([&] { hf::load_color(text); }).find(text), std::string::npos);

  // 8-bit "depth" is refused: its units are unknown.
  const std::string eight = dir / "eight.png";
  ASSERT_TRUE(cv::imwrite(eight, cv::Mat(2, 2, CV_8UC1, cv::Scalar(9))));
  const std::string msg = error_of([&] { hf::load_depth(eight); });
  EXPECT_NE(msg.find(eight), std::string::npos);
  EXPECT_NE(msg.find("16-bit"), std::string::npos);
}

TEST(ImageIo, WritesAreAtomicAndFailuresLeaveNothing) {
  TempDir dir("atomic");
  const std::string path = dir / "d.png";
  hf::write_depth_png(path, hf::DepthImage(4, 4, 1.0f));
  hf::write_depth_png(path, hf::DepthImage(4, 4, 2.0f));  // replaces
  EXPECT_FLOAT_EQ(hf::load_depth(path)(3, 3), 2.0f);
  size_t files = 0;
  for (const auto& e : fs::directory_iterator(dir.path)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);  // no temporary left behind

  const std::string bad = dir / "no_such_folder/d.png";
  EXPECT_NE(error_of([&] { hf::write_depth_png(bad, hf::DepthImage(2, 2, 1.0f)); }).find(bad), std::string::npos);
  EXPECT_NE(error_of([&] { hf::write_color_png(bad, hf::ColorImage(2, 2)); }).find(bad), std::string::npos);
  EXPECT_FALSE(error_of([&] { hf::write_depth_png(path, hf::DepthImage()); }).empty());
  EXPECT_FALSE(error_of([&] { hf::write_color_png(path, hf::ColorImage()); }).empty());
  EXPECT_FALSE(error_of([&] { hf::write_depth_png(path, hf::DepthImage(2, 2), 0.0); }).empty());
  EXPECT_FLOAT_EQ(hf::load_depth(path)(3, 3), 2.0f);  // failed writes left the old file alone
}

// Issue 14.10: decode by content, check the decoded type against the role.
TEST(ImageIo, ContentDecidesAndMustMatchTheNameAndRole) {
  TempDir dir("content");
  const std::string jpg = dir / "c.jpg";
  ASSERT_TRUE(cv::imwrite(jpg, cv::Mat(4, 4, CV_8UC3, cv::Scalar(10, 20, 30))));
  EXPECT_EQ(hf::load_color(jpg).width(), 4);
  const std::string renamed = dir / "c.png";
  fs::rename(jpg, renamed);
  const std::string e = error_of([&] { hf::load_color(renamed); });
  EXPECT_NE(e.find(renamed + ": colour image holds JPEG data but its name says PNG"), std::string::npos) << e;
  // A colour PNG as depth, a depth PNG as colour: refused by what they decode to.
  const std::string colour = dir / "colour.png";
  ASSERT_TRUE(cv::imwrite(colour, cv::Mat(4, 4, CV_16UC3, cv::Scalar(1000, 1000, 1000))));
  EXPECT_NE(error_of([&] { hf::load_depth(colour); }).find("single-channel depth image, got 3 channels"), std::string::npos);
  const std::string depth = dir / "depth.png";
  hf::write_depth_png(depth, hf::DepthImage(4, 4, 1.0f));
  EXPECT_NE(error_of([&] { hf::load_color(depth); }).find("16-bit single-channel image (a depth map?)"), std::string::npos);
  // Alpha is dropped, not mistaken for a channel.
  const std::string rgba = dir / "rgba.png";
  ASSERT_TRUE(cv::imwrite(rgba, cv::Mat(2, 2, CV_8UC4, cv::Scalar(30, 20, 10, 128))));
  const hf::ColorImage c = hf::load_color(rgba);
  EXPECT_EQ(c(1, 1).r, 10);
  EXPECT_EQ(c(1, 1).b, 30);
}

// Issue 14.7: images are opened only as regular files; the smaller item "--plot with no extension" came from
// writers choosing the format by name: they now always write PNG.
TEST(ImageIo, FifoIsRefusedAndWritersIgnoreTheName) {
  TempDir dir("kinds");
  const std::string fifo = dir / "f.png";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  EXPECT_NE(error_of([&] { hf::load_color(fifo); }).find("FIFO"), std::string::npos);
  const std::string no_ext = dir / "plot";
  hf::ColorImage c(3, 2);
  c(2, 1) = hf::Rgb8{1, 2, 3};
  hf::write_color_png(no_ext, c);
  std::ifstream in(no_ext, std::ios::binary);
  char magic[4] = {};
  in.read(magic, 4);
  EXPECT_EQ(std::string(magic + 1, 3), "PNG");
  EXPECT_EQ(hf::load_color(no_ext)(2, 1).b, 3);
}

namespace {

// The bytes of an 8x6 image of `type` encoded as `ext` by OpenCV.
std::string encoded_8x6(const std::string& ext, int type) {
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(ext, cv::Mat(6, 8, type, cv::Scalar::all(100)), bytes));
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace

// Issue 35: a small file whose header promises a huge image is refused from its header, before any decoding.
TEST(ImageIo, HeaderSizeCheckedBeforeDecoding) {
  for (const char* ext : {".png", ".jpg", ".tiff", ".bmp"}) {
    const std::optional<hf::ImageHeaderSize> size = hf::image_header_size(encoded_8x6(ext, CV_8UC3));
    ASSERT_TRUE(size.has_value()) << ext;
    EXPECT_EQ(size->width, 8u) << ext;
    EXPECT_EQ(size->height, 6u) << ext;
  }
  EXPECT_FALSE(hf::image_header_size("\x89PNG\r\n\x1a\n").has_value());  // too short to say
  EXPECT_FALSE(hf::image_header_size(std::string("\xff\xd8\xff\xe0\x00\x01", 6)).has_value());  // bad length

  // An 8x6 16-bit PNG whose IHDR is rewritten to 20000x20000 (the CRC no longer matches: never looked at).
  TempDir dir("image_header");
  std::string bomb = encoded_8x6(".png", CV_16UC1);
  for (int k = 0; k < 2; ++k) {
    const std::uint32_t v = 20000;
    for (int b = 0; b < 4; ++b) bomb[size_t(16 + 4 * k + b)] = char((v >> (24 - 8 * b)) & 0xff);
  }
  const std::string path = dir / "bomb.png";
  std::ofstream(path, std::ios::binary) << bomb;
  EXPECT_EQ(error_of([&] { hf::load_depth(path, {}, {640, 480}); }),
            path + ": depth image is 20000x20000 (its PNG IHDR) but the camera is 640x480; not decoded");
  EXPECT_EQ(error_of([&] { hf::load_depth(path); }),
            path + ": depth image is 20000x20000 (its PNG IHDR), more than the 67108864-pixel limit; not decoded");
  // The expected size passes and the image decodes as before.
  const std::string good = dir / "good.png";
  std::ofstream(good, std::ios::binary) << encoded_8x6(".png", CV_16UC1);
  EXPECT_EQ(hf::load_depth(good, {}, {8, 6}).width(), 8);
  EXPECT_NE(error_of([&] { hf::load_color(good, {640, 480}); }).find("colour image is 8x6 (its PNG IHDR) but the camera"),
            std::string::npos);
}
