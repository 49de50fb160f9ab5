// Camera pixel formats (io/pixel_formats.h) on synthetic buffers, and the libcamera back-end's frame path
// (io/libcamera_capture.h): exact values where the format is lossless, BT.601 reference colours within the
// integer arithmetic's rounding, strides, and a clear error for every short or malformed buffer.
#include "io/pixel_formats.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>
#include <random>

#include "core/error.h"
#include "io/libcamera_capture.h"
#if HF_HAVE_LIBCAMERA
#include <libcamera/formats.h>
#endif

namespace {

using hf::PixelFormat;

std::vector<std::uint8_t> random_bytes(size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> b(0, 255);
  std::vector<std::uint8_t> v(n);
  for (auto& x : v) x = std::uint8_t(b(rng));
  return v;
}

// The BT.601 limited-range colour of (Y, Cb, Cr) from the standard's real coefficients, for comparison.
hf::Rgb8 bt601(double y, double u, double v) {
  auto c = [](double x) { return std::uint8_t(std::clamp(std::lround(x), 0L, 255L)); };
  const double yy = 1.164383 * (y - 16);
  return {c(yy + 1.596027 * (v - 128)), c(yy - 0.391762 * (u - 128) - 0.812968 * (v - 128)),
          c(yy + 2.017232 * (u - 128))};
}

void expect_near(const hf::Rgb8& a, const hf::Rgb8& b, int tolerance, const std::string& what) {
  EXPECT_LE(std::abs(a.r - b.r), tolerance) << what;
  EXPECT_LE(std::abs(a.g - b.g), tolerance) << what;
  EXPECT_LE(std::abs(a.b - b.b), tolerance) << what;
}

}  // namespace

TEST(PixelFormats, YuyvAndUyvyMatchBt601) {
  // Two pixels per 4 bytes; black, white and the six saturated colours plus random samples.
  const std::vector<std::array<int, 3>> samples = {{16, 128, 128}, {235, 128, 128}, {81, 90, 240}, {145, 54, 34},
                                                   {41, 240, 110}, {170, 166, 16},  {106, 202, 222}, {210, 16, 146}};
  const int w = int(samples.size()) * 2;
  std::vector<std::uint8_t> yuyv, uyvy;
  for (const auto& s : samples) {
    yuyv.insert(yuyv.end(), {std::uint8_t(s[0]), std::uint8_t(s[1]), std::uint8_t(s[0]), std::uint8_t(s[2])});
    uyvy.insert(uyvy.end(), {std::uint8_t(s[1]), std::uint8_t(s[0]), std::uint8_t(s[2]), std::uint8_t(s[0])});
  }
  const hf::ColorImage a = hf::decode_color(PixelFormat::yuyv, yuyv.data(), yuyv.size(), w, 1);
  const hf::ColorImage b = hf::decode_color(PixelFormat::uyvy, uyvy.data(), uyvy.size(), w, 1);
  EXPECT_EQ(a.pixels(), b.pixels());
  for (size_t i = 0; i < samples.size(); ++i) {
    // The integer coefficients are the standard's times 256, rounded: at most 1 level apart over the range.
    const hf::Rgb8 want = bt601(samples[i][0], samples[i][1], samples[i][2]);
    expect_near(a(int(2 * i), 0), want, 1, "sample " + std::to_string(i));
    EXPECT_EQ(a(int(2 * i), 0), a(int(2 * i + 1), 0));
  }
  EXPECT_EQ(a(0, 0), (hf::Rgb8{0, 0, 0}));
  EXPECT_EQ(a(2, 0), (hf::Rgb8{255, 255, 255}));
}

TEST(PixelFormats, PackedRgbLayoutsWithRowPaddingAreExact) {
  const int w = 5, h = 3;
  const size_t stride = 32;  // padded rows, as drivers align them
  const std::vector<std::uint8_t> bytes = random_bytes(stride * h, 3);
  struct Case {
    PixelFormat f;
    int step, r, g, b;
  };
  for (const Case& c : {Case{PixelFormat::rgb24, 3, 0, 1, 2}, Case{PixelFormat::bgr24, 3, 2, 1, 0},
                        Case{PixelFormat::xbgr32, 4, 0, 1, 2}, Case{PixelFormat::xrgb32, 4, 2, 1, 0}}) {
    const hf::ColorImage img = hf::decode_color(c.f, bytes.data(), bytes.size(), w, h, stride);
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const std::uint8_t* p = bytes.data() + size_t(y) * stride + size_t(x) * c.step;
        EXPECT_EQ(img(x, y), (hf::Rgb8{p[c.r], p[c.g], p[c.b]})) << hf::to_string(c.f) << " " << x << "," << y;
      }
  }
}

TEST(PixelFormats, Nv12SharesChromaOverTwoByTwoBlocks) {
  const int w = 4, h = 2;
  std::vector<std::uint8_t> nv12 = {16, 235, 81, 145, 16, 235, 81, 145,  // luma rows
                                    128, 128, 90, 240};                  // one chroma row: (U, V) per 2x2
  const hf::ColorImage img = hf::decode_color(PixelFormat::nv12, nv12.data(), nv12.size(), w, h);
  for (int y = 0; y < 2; ++y) {
    expect_near(img(0, y), bt601(16, 128, 128), 1, "black");
    expect_near(img(1, y), bt601(235, 128, 128), 1, "white");
    expect_near(img(2, y), bt601(81, 90, 240), 1, "red");
    expect_near(img(3, y), bt601(145, 90, 240), 1, "light red");
  }
}

TEST(PixelFormats, MjpegDecodesAndChecksItsSize) {
  cv::Mat bgr(24, 32, CV_8UC3);
  for (int y = 0; y < bgr.rows; ++y)
    for (int x = 0; x < bgr.cols; ++x) bgr.at<cv::Vec3b>(y, x) = {std::uint8_t(8 * x), std::uint8_t(10 * y), 128};
  std::vector<std::uint8_t> jpeg;
  cv::imencode(".jpg", bgr, jpeg, {cv::IMWRITE_JPEG_QUALITY, 100});
  const hf::ColorImage img = hf::decode_color(PixelFormat::mjpeg, jpeg.data(), jpeg.size(), 32, 24);
  // Quality 100 still subsamples chroma; a smooth ramp comes back within a few levels.
  for (int y = 0; y < 24; y += 5)
    for (int x = 0; x < 32; x += 5) expect_near(img(x, y), {128, std::uint8_t(10 * y), std::uint8_t(8 * x)}, 6, "ramp");
  EXPECT_THROW(hf::decode_color(PixelFormat::mjpeg, jpeg.data(), jpeg.size(), 64, 48), hf::Error);
  jpeg.resize(jpeg.size() / 3);  // a truncated transfer
  try {
    hf::decode_color(PixelFormat::mjpeg, jpeg.data(), 20, 32, 24);
    FAIL() << "a 20-byte JPEG decoded";
  } catch (const hf::Error& e) {
    EXPECT_NE(std::string(e.what()).find("mjpeg frame"), std::string::npos) << e.what();
  }
}

TEST(PixelFormats, Z16IsLittleEndianUnitsTimesTheScale) {
  const std::vector<std::uint8_t> raw = {0x00, 0x00, 0xe8, 0x03, 0xff, 0xff, 0x01, 0x00};  // 0, 1000, 65535, 1
  const hf::DepthImage d = hf::decode_z16(raw.data(), raw.size(), 2, 2, 0, 0.001);
  EXPECT_EQ(d(0, 0), 0.0f);
  EXPECT_EQ(d(1, 0), 1.0f);
  EXPECT_EQ(d(0, 1), float(65.535));
  EXPECT_EQ(d(1, 1), float(0.001));
  EXPECT_THROW(hf::decode_z16(raw.data(), raw.size(), 2, 2, 0, 0.0), hf::Error);
}

TEST(PixelFormats, ShortOrMalformedBuffersAreErrorsNamingTheFormat) {
  const std::vector<std::uint8_t> bytes(100);
  auto message = [&](auto&& f) {
    try {
      f();
    } catch (const hf::Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message([&] { hf::decode_color(PixelFormat::yuyv, bytes.data(), bytes.size(), 10, 10); })
                .find("yuyv frame of 100 bytes, expected at least 200"),
            std::string::npos);
  EXPECT_NE(message([&] { hf::decode_color(PixelFormat::yuyv, bytes.data(), bytes.size(), 3, 2); }).find("odd"),
            std::string::npos);
  EXPECT_NE(message([&] { hf::decode_color(PixelFormat::rgb24, bytes.data(), bytes.size(), 4, 2, 8); })
                .find("stride 8 bytes is shorter"),
            std::string::npos);
  EXPECT_NE(message([&] { hf::decode_color(PixelFormat::nv12, bytes.data(), bytes.size(), 10, 10); })
                .find("nv12 frame of 100 bytes"),
            std::string::npos);
  EXPECT_NE(message([&] { hf::decode_z16(bytes.data(), bytes.size(), 10, 10, 0, 0.001); }).find("z16 frame"),
            std::string::npos);
  EXPECT_NE(message([&] { hf::decode_color(PixelFormat::z16, bytes.data(), bytes.size(), 2, 2); }).find("depth"),
            std::string::npos);
}

TEST(PixelFormats, V4l2FourccsMapToTheirLayouts) {
  auto cc = [](const char* s) {
    return std::uint32_t(std::uint8_t(s[0])) | (std::uint32_t(std::uint8_t(s[1])) << 8) |
           (std::uint32_t(std::uint8_t(s[2])) << 16) | (std::uint32_t(std::uint8_t(s[3])) << 24);
  };
  EXPECT_EQ(hf::pixel_format_from_v4l2(cc("YUYV")), PixelFormat::yuyv);
  EXPECT_EQ(hf::pixel_format_from_v4l2(cc("MJPG")), PixelFormat::mjpeg);
  EXPECT_EQ(hf::pixel_format_from_v4l2(cc("RGB3")), PixelFormat::rgb24);
  EXPECT_EQ(hf::pixel_format_from_v4l2(cc("Z16 ")), PixelFormat::z16);
  EXPECT_FALSE(hf::pixel_format_from_v4l2(cc("H264")));
  EXPECT_EQ(hf::fourcc_text(cc("Z16 ")), "Z16 ");
}

TEST(LibcameraFrames, DrmFourccsFollowLittleEndianWordOrder) {
#if HF_HAVE_LIBCAMERA
  // The constants of libcamera itself, so a renamed or reordered format cannot slip past.
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::RGB888.fourcc()), PixelFormat::bgr24);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::BGR888.fourcc()), PixelFormat::rgb24);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::XRGB8888.fourcc()), PixelFormat::xrgb32);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::XBGR8888.fourcc()), PixelFormat::xbgr32);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::YUYV.fourcc()), PixelFormat::yuyv);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::NV12.fourcc()), PixelFormat::nv12);
  EXPECT_EQ(hf::pixel_format_from_libcamera(libcamera::formats::MJPEG.fourcc()), PixelFormat::mjpeg);
  EXPECT_FALSE(hf::pixel_format_from_libcamera(libcamera::formats::SRGGB10.fourcc()));
#else
  GTEST_SKIP() << "libcamera not built in: the fourcc constants cannot be checked against libcamera's";
#endif
}

TEST(LibcameraFrames, TwoPlaneNv12ReadsLikeOneContiguousBuffer) {
  const int w = 8, h = 4;
  const std::vector<std::uint8_t> all = random_bytes(size_t(w) * h * 3 / 2, 5);
  const std::uint32_t nv12 = 0x3231564e;  // 'N','V','1','2'
  const hf::ColorImage one = hf::libcamera_planes_to_rgb(nv12, {{all.data(), all.size()}}, w, h, w);
  const hf::ColorImage two = hf::libcamera_planes_to_rgb(
      nv12, {{all.data(), size_t(w) * h}, {all.data() + size_t(w) * h, all.size() - size_t(w) * h}}, w, h, w);
  EXPECT_EQ(one.pixels(), two.pixels());
  EXPECT_EQ(one.pixels(), hf::decode_color(PixelFormat::nv12, all.data(), all.size(), w, h).pixels());
  // libcamera's RGB888 (B, G, R in memory) decoded through the frame path.
  const std::vector<std::uint8_t> bgr = {10, 20, 30, 40, 50, 60};
  const hf::ColorImage px = hf::libcamera_planes_to_rgb(0x34324752 /* RG24 */, {{bgr.data(), bgr.size()}}, 2, 1, 6);
  EXPECT_EQ(px(0, 0), (hf::Rgb8{30, 20, 10}));
  EXPECT_EQ(px(1, 0), (hf::Rgb8{60, 50, 40}));
  EXPECT_THROW(hf::libcamera_planes_to_rgb(0x30314752 /* RG10 */, {{bgr.data(), bgr.size()}}, 2, 1, 6), hf::Error);
}
