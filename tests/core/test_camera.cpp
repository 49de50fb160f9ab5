#include "core/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <filesystem>
#include <fstream>
#include <unistd.h>
#include <random>

#include "core/error.h"

namespace hf {
namespace {

std::string error_of(const std::string& text, const std::string& name) {
  try {
    PinholeCamera::parse(text, name);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(Camera, ProjectBackprojectRoundTrip) {
  const PinholeCamera cam = PinholeCamera::preset("fr1");
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> ux(0.0, cam.width - 1.0), uy(0.0, cam.height - 1.0), ud(0.1, 10.0);
  for (int i = 0; i < 1000; ++i) {
    const Eigen::Vector2d p(ux(rng), uy(rng));
    const double d = ud(rng);
    const Eigen::Vector3d v = cam.backproject(p.x(), p.y(), d);
    EXPECT_DOUBLE_EQ(v.z(), d);
    EXPECT_LT((cam.project(v) - p).norm(), 1e-9);
    EXPECT_TRUE(cam.in_image(cam.project(v)));
    // Back-projecting the projection of a point gives the point back.
    const Eigen::Vector3d q = cam.backproject(cam.project(v).x(), cam.project(v).y(), v.z());
    EXPECT_LT((q - v).norm(), 1e-12 * (1.0 + v.norm()));
  }
}

TEST(Camera, KMatchesProjection) {
  const PinholeCamera cam = PinholeCamera::preset("fr3");
  const Eigen::Matrix3d K = cam.K();
  EXPECT_EQ(K(0, 0), cam.fx);
  EXPECT_EQ(K(1, 1), cam.fy);
  EXPECT_EQ(K(0, 2), cam.cx);
  EXPECT_EQ(K(1, 2), cam.cy);
  EXPECT_EQ(K(2, 2), 1.0);
  EXPECT_EQ(K(0, 1), 0.0);
  EXPECT_EQ(K(1, 0), 0.0);
  EXPECT_EQ(K(2, 0), 0.0);
  EXPECT_EQ(K(2, 1), 0.0);
  const Eigen::Vector3d v(0.3, -0.2, 1.7);
  const Eigen::Vector3d h = K * v;
  EXPECT_LT((h.hnormalized() - cam.project(v)).norm(), 1e-12);
  EXPECT_LT((K.inverse() * Eigen::Vector3d(100.0, 50.0, 1.0) * 2.0 - cam.backproject(100.0, 50.0, 2.0)).norm(), 1e-12);
}

TEST(Camera, KernelIntrinsicsAgreeWithDouble) {
  const PinholeCamera cam = PinholeCamera::preset("fr2");
  const hf_intrinsics K = cam.kernel_intrinsics();
  const hf_float4 v = hf_backproject(K, 100.0f, 200.0f, 1.5f);
  const Eigen::Vector3d e = cam.backproject(100.0, 200.0, 1.5);
  EXPECT_NEAR(v.x, e.x(), 1e-6);
  EXPECT_NEAR(v.y, e.y(), 1e-6);
  EXPECT_EQ(v.w, 1.0f);
  float px, py;
  hf_project(K, v, &px, &py);
  EXPECT_NEAR(px, 100.0f, 1e-4f);
  EXPECT_NEAR(py, 200.0f, 1e-4f);
  EXPECT_EQ(K.width, 640);
}

TEST(Camera, ScaledLevels) {
  const PinholeCamera cam = PinholeCamera::preset("ros");
  EXPECT_EQ(cam.scaled(0), cam);
  const PinholeCamera c1 = cam.scaled(1);
  EXPECT_DOUBLE_EQ(c1.fx, 262.5);
  EXPECT_DOUBLE_EQ(c1.fy, 262.5);
  EXPECT_DOUBLE_EQ(c1.cx, 159.5);  // (319.5 + 0.5) / 2 - 0.5
  EXPECT_DOUBLE_EQ(c1.cy, 119.5);
  EXPECT_EQ(c1.width, 320);
  EXPECT_EQ(c1.height, 240);
  EXPECT_EQ(cam.scaled(3), c1.scaled(2));
  EXPECT_EQ(cam.scaled(3).width, 80);
  PinholeCamera odd = cam;
  odd.width = 641;
  odd.height = 479;
  EXPECT_EQ(odd.scaled(1).width, 320);
  EXPECT_EQ(odd.scaled(1).height, 239);
  // Pixel (x, y) of level l covers level-0 pixels 2^l x .. 2^l x + 2^l - 1: its centre (2^l (x + 0.5) - 0.5)
  // lies on the same ray.
  for (int l = 1; l <= 4; ++l) {
    const PinholeCamera cl = cam.scaled(l);
    const double s = double(1 << l);
    for (double x : {0.0, 7.0, 13.25}) {
      const double x0 = s * (x + 0.5) - 0.5;
      EXPECT_LT((cl.backproject(x, x * 0.5, 2.0) - cam.backproject(x0, s * (x * 0.5 + 0.5) - 0.5, 2.0)).norm(), 1e-12);
    }
  }
}

TEST(Camera, PresetsAndUnknownPreset) {
  const auto names = PinholeCamera::preset_names();
  EXPECT_EQ(names.size(), 7u);
  for (const auto& n : names) EXPECT_NO_THROW(PinholeCamera::preset(n)) << n;
  const PinholeCamera fr1 = PinholeCamera::preset("fr1");
  EXPECT_DOUBLE_EQ(fr1.fx, 517.3);
  EXPECT_DOUBLE_EQ(fr1.cy, 255.3);
  EXPECT_DOUBLE_EQ(PinholeCamera::preset("7scenes").fx, 585.0);
  const PinholeCamera fr1_registered = PinholeCamera::preset("fr1-registered");
  EXPECT_DOUBLE_EQ(fr1_registered.fx, 532.0);
  EXPECT_DOUBLE_EQ(fr1_registered.cx, 309.5);
  EXPECT_TRUE(fr1_registered.distortion.none());
  EXPECT_DOUBLE_EQ(PinholeCamera::preset("icl-nuim").fx, 481.2);
  try {
    PinholeCamera::preset("fr4");
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("fr4"), std::string::npos) << what;
    EXPECT_NE(what.find("fr1"), std::string::npos) << "the message should list the known presets: " << what;
  }
}

TEST(CameraFile, ParsesJsonAndKeyValue) {
  const PinholeCamera j = PinholeCamera::parse(
      R"({"fx": 500.5, "fy": 501, "cx": 320, "cy": 240.25, "width": 640, "height": 480})", "cam.json");
  EXPECT_EQ(j, (PinholeCamera{500.5, 501.0, 320.0, 240.25, 640, 480}));
  const PinholeCamera k = PinholeCamera::parse(
      "# calibration\nfx 500.5\nfy 501   # comment\n\ncx 320\ncy 240.25\nwidth 640\nheight 480\n", "cam.txt");
  EXPECT_EQ(k, j);
}

TEST(CameraFile, ErrorsNameFileAndLine) {
  const std::string json_bad = "{\n  \"fx\": 500,\n  \"fy\": oops\n}";
  EXPECT_EQ(error_of(json_bad, "cam.json").rfind("cam.json:3: expected", 0), 0u) << error_of(json_bad, "cam.json");
  const std::string json_missing = R"({"fx": 500, "fy": 500, "cx": 1, "cy": 2, "width": 640})";
  EXPECT_NE(error_of(json_missing, "c.json").find("height"), std::string::npos);
  EXPECT_EQ(error_of(json_missing, "c.json").rfind("c.json: ", 0), 0u);
  EXPECT_EQ(error_of("fx 500\nfy abc\n", "k.txt").rfind("k.txt:2: expected", 0), 0u) << error_of("fx 500\nfy abc\n", "k.txt");
  EXPECT_EQ(error_of("fx 500\n\nfoo 3\n", "k.txt").rfind("k.txt:3: expected", 0), 0u);
  EXPECT_EQ(error_of("fx 500 501\n", "k.txt").rfind("k.txt:1: expected", 0), 0u);
  EXPECT_EQ(error_of("fx nan\n", "k.txt").rfind("k.txt:1: expected", 0), 0u);
  EXPECT_NE(error_of("fx 500\nfy 500\ncx 1\ncy 2\nwidth 640\n", "k.txt").find("missing 'height'"), std::string::npos);
  EXPECT_NE(error_of("fx -5\nfy 500\ncx 1\ncy 2\nwidth 640\nheight 480\n", "k.txt").find("k.txt:1: expected fx"),
            std::string::npos);
  EXPECT_NE(error_of("fx 5\nfy 500\ncx 1\ncy 2\nwidth 0\nheight 480\n", "k.txt").find("k.txt: expected"),
            std::string::npos);
  EXPECT_NE(error_of(R"({"fx": 5, "fy": 5, "cx": 1, "cy": 2, "width": 1e9, "height": 480})", "c.json").find("c.json"),
            std::string::npos);
  EXPECT_NE(error_of("", "empty.txt").find("empty.txt"), std::string::npos);
  EXPECT_NE(error_of(R"({"fx": "500"})", "c.json").find("c.json"), std::string::npos);
}

// Issue 35: finite but absurd intrinsics, unknown JSON keys and repeated keys are refused at their line.
TEST(CameraFile, BoundsUnknownAndRepeatedKeysNamed) {
  const std::string tail = "cx 320\ncy 240\nwidth 640\nheight 480\n";
  // 640 px wide: focal lengths 0.0437 * 640 = 27.97 .. 114.6 * 640 = 73344 px (fields of view 170 .. 0.5 degrees).
  EXPECT_EQ(error_of("fx 1e-300\nfy 500\n" + tail, "k.txt"),
            "k.txt:1: expected fx within 27.968..73344 px (fields of view 0.5..170 degrees over 640 px), got 1e-300");
  EXPECT_EQ(error_of("fy 500\nfx 1e300\n" + tail, "k.txt").rfind("k.txt:2: expected fx within", 0), 0u);
  EXPECT_EQ(error_of("fx 500\nfy 500\ncx 1e9\ncy 240\nwidth 640\nheight 480\n", "k.txt"),
            "k.txt:3: expected cx within -640..1280 px (the principal point near the image), got 1e+09");
  EXPECT_NO_THROW(PinholeCamera::parse("fx 28\nfy 21\n" + tail, "k.txt"));     // just inside: 169.7 degrees
  EXPECT_NO_THROW(PinholeCamera::parse("fx 73000\nfy 500\n" + tail, "k.txt"));  // 0.5 degrees
  EXPECT_EQ(error_of("fx 500\nfy 500\nfx 1\n" + tail, "k.txt"), "k.txt:3: 'fx' given twice (first on line 1)");
  const std::string json =
      "{\"fx\": 500, \"fy\": 500, \"cx\": 320, \"cy\": 240,\n \"k4\": 0.1, \"width\": 640, \"height\": 480}";
  EXPECT_EQ(error_of(json, "c.json"),
            "c.json:2: expected only the keys fx fy cx cy width height k1 k2 p1 p2 k3, got 'k4'");
  const std::string json_far =
      "{\"fx\": 500,\n\"fy\": 1e300, \"cx\": 320, \"cy\": 240, \"width\": 640, \"height\": 480}";
  EXPECT_EQ(error_of(json_far, "c.json").rfind("c.json:2: expected fy within", 0), 0u) << error_of(json_far, "c.json");
}

// Issue 34: lens distortion (k1 k2 p1 p2 k3) in both forms of the one schema, optional, validated at its line.
TEST(CameraFile, LensDistortion) {
  const std::string base = "fx 517.3\nfy 516.5\ncx 318.6\ncy 255.3\nwidth 640\nheight 480\n";
  EXPECT_TRUE(PinholeCamera::parse(base, "k.txt").distortion.none());
  const PinholeCamera t =
      PinholeCamera::parse(base + "k1 0.2624\nk2 -0.9531\np1 -0.0054\np2 0.0026\nk3 1.1633\n", "k.txt");
  EXPECT_EQ(t, PinholeCamera::preset("fr1"));
  const PinholeCamera j = PinholeCamera::parse(
      R"({"fx": 517.3, "fy": 516.5, "cx": 318.6, "cy": 255.3, "width": 640, "height": 480,
          "k1": 0.2624, "k2": -0.9531, "p1": -0.0054, "p2": 0.0026, "k3": 1.1633})", "c.json");
  EXPECT_EQ(j, t);
  EXPECT_EQ(PinholeCamera::parse(base + "k2 0.5\n", "k.txt").distortion, (LensDistortion{0.0, 0.5, 0.0, 0.0, 0.0}));
  EXPECT_EQ(PinholeCamera::preset("fr1").pinhole(), (PinholeCamera{517.3, 516.5, 318.6, 255.3, 640, 480}));
  EXPECT_TRUE(PinholeCamera::preset("fr3").distortion.none());
  EXPECT_NE(PinholeCamera::preset("fr1").describe().find("k1=0.2624"), std::string::npos);
  // Non-finite, huge and repeated values at their line.
  EXPECT_EQ(error_of(base + "k1 nan\n", "k.txt").rfind("k.txt:7: expected", 0), 0u);
  EXPECT_EQ(error_of(base + "k1 inf\n", "k.txt").rfind("k.txt:7: expected", 0), 0u);
  EXPECT_EQ(error_of(base + "k1 0.1\nk2 1e300\n", "k.txt"), "k.txt:8: expected k2 within -1000..1000, got 1e+300");
  EXPECT_EQ(error_of(base + "p2 2\n", "k.txt"), "k.txt:7: expected p2 within -1..1, got 2");
  EXPECT_EQ(error_of(base + "k3 1\nk3 1\n", "k.txt"), "k.txt:8: 'k3' given twice (first on line 7)");
  EXPECT_EQ(error_of(R"({"fx": 517, "fy": 516, "cx": 318, "cy": 255, "width": 640, "height": 480,
                       "k1": 1e400})", "c.json").rfind("c.json: expected a JSON camera object", 0), 0u);
  EXPECT_EQ(error_of("{\"fx\": 517, \"fy\": 516, \"cx\": 318, \"cy\": 255, \"width\": 640, \"height\": 480,\n"
                     "\"k1\": 2000}", "c.json"), "c.json:2: expected k1 within -1000..1000, got 2000");
  // A radial term that folds the image back inside the frame: r (1 + k1 r^2) has slope 1 + 3 k1 r^2, which k1 = -1
  // turns negative at r = 0.577, inside the corners' 0.78.
  const std::string folded = error_of(base + "k1 -1\n", "k.txt");
  EXPECT_EQ(folded.rfind("k.txt:7: expected a distortion whose image radius grows", 0), 0u) << folded;
  EXPECT_NE(folded.find("0.57"), std::string::npos) << folded;
  // The same lens on a narrow crop never reaches the fold: accepted.
  EXPECT_NO_THROW(PinholeCamera::parse("fx 517.3\nfy 516.5\ncx 100\ncy 100\nwidth 200\nheight 200\nk1 -1\n", "k.txt"));
}

TEST(CameraFile, SaveLoadRoundTripAndMissingFile) {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_camera_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "cam.json").string();
  const PinholeCamera cam = PinholeCamera::preset("fr2");
  ASSERT_FALSE(cam.distortion.none());
  cam.save(path);
  EXPECT_EQ(PinholeCamera::load(path), cam);  // distortion included
  try {
    PinholeCamera::load((dir / "missing.json").string());
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("missing.json"), std::string::npos);
  }
  std::ofstream((dir / "bad.txt").string()) << "fx 1\nfy x\n";
  try {
    PinholeCamera::load((dir / "bad.txt").string());
    FAIL() << "expected hf::ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 2);
    EXPECT_EQ(std::string(e.what()).rfind((dir / "bad.txt").string() + ":2:", 0), 0u);
  }
  std::filesystem::remove_all(dir);
  EXPECT_NE(cam.describe().find("640x480"), std::string::npos);
}

}  // namespace
}  // namespace hf
