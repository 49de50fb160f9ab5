// 7-Scenes reader: pose and intrinsics text, folder listing, millimetre depth with 65535 invalid, synthesised
// stamps, ground truth from the pose files.
#include "io/seven_scenes.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "tests/io/test_dataset_util.h"

using hf::test::contains;
using hf::test::error_of;
using hf::test::TempDir;
using hf::test::write_text;

namespace {

const char* kPose =
    "9.093128999999999795e-01 2.726222899999999894e-01 -3.142243299999999961e-01 -3.404563400000000239e-01\n"
    "-2.724861800000000223e-01 9.610497999999999541e-01 4.527962600000000337e-02 1.646981800000000065e-02\n"
    "3.143392500000000145e-01 4.444964600000000238e-02 9.482093499999999509e-01 2.965691699999999931e-01\n"
    "0.000000000000000000e+00 0.000000000000000000e+00 0.000000000000000000e+00 1.000000000000000000e+00\n";

std::string translation_pose(double x) {
  return "1 0 0 " + std::to_string(x) + "\n0 1 0 0\n0 0 1 0\n0 0 0 1\n";
}

}  // namespace

TEST(SevenScenesText, PoseIsCameraToWorld) {
  const hf::SE3 T = hf::parse_seven_scenes_pose(kPose, "frame-000000.pose.txt");
  EXPECT_NEAR((T.translation() - Eigen::Vector3d(-0.34045634, 0.016469818, 0.29656917)).norm(), 0.0, 1e-8);
  // KinectFusion's rotations are orthonormal to about 4e-5 only; the nearest rotation moves entries by as much.
  EXPECT_NEAR(T.rotation()(0, 1), 0.27262229, 1e-4);
  EXPECT_NEAR(T.rotation()(2, 0), 0.31433925, 1e-4);
  EXPECT_NEAR((T.rotation().transpose() * T.rotation() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-12);
  // Blank lines and any whitespace are fine.
  EXPECT_NO_THROW(hf::parse_seven_scenes_pose("\n1 0 0 0\n\n0\t1 0 0\n0 0 1 0\r\n0 0 0 1", "p"));
}

TEST(SevenScenesText, MalformedPosesNameFileAndLine) {
  struct Case {
    std::string text;
    std::string expect;
  };
  const Case cases[] = {
      {"1 0 0 0\n0 1 0 0\n0 0 1 0\n", "p.txt: expected 4 lines of 4 numbers, got 3"},
      {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n1 2 3 4\n", "p.txt:5: expected 4 lines"},
      {"1 0 0 0\n0 1 0\n0 0 1 0\n0 0 0 1\n", "p.txt:2: expected 4 numbers on the line, got 3"},
      {"1 0 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "p.txt:1: expected 4 numbers on the line, got more"},
      {"1 0 0 0\n0 1 0 0\n0 0 1 nan\n0 0 0 1\n", "p.txt:3: expected a finite number, got 'nan'"},
      {"1 0 0 0\n0 1 0 0\n0 0 1 -inf\n0 0 0 1\n", "p.txt:3: expected a finite number"},
      {"1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 1 1\n", "p.txt:4: expected the last row '0 0 0 1'"},
      {"2 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "expected a rotation"},
      {"-1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "expected a rotation"},  // a reflection
      {"", "expected 4 lines of 4 numbers, got 0"},
      // Issue 35: a finite but absurd translation hung the trajectory plot; the TUM reader's 1e6 m bound, at its line.
      {"1 0 0 0\n\n0 1 0 1e308\n0 0 1 0\n0 0 0 1\n", "p.txt:3: expected a translation within 1e6 m (a physical bound), got 1e+308"},
      {"1 0 0 -1000001\n0 1 0 0\n0 0 1 0\n0 0 0 1\n", "p.txt:1: expected a translation within 1e6 m"},
  };
  for (const Case& c : cases) EXPECT_TRUE(contains(error_of([&] { hf::parse_seven_scenes_pose(c.text, "p.txt"); }), c.expect)) << c.text;
}

TEST(SevenScenesText, Intrinsics) {
  const hf::PinholeCamera c = hf::parse_seven_scenes_intrinsics(
      "5.85e+02 0.0 3.2e+02\n0.0 5.85e+02 2.4e+02\n0.0 0.0 1.0\n", "camera-intrinsics.txt");
  EXPECT_EQ(c, hf::PinholeCamera::preset("7scenes"));
  EXPECT_EQ(hf::parse_seven_scenes_intrinsics("500 0 100\n0 510 80\n0 0 1", "k", 200, 160).width, 200);
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("500 1 100\n0 510 80\n0 0 1", "k"); }), "skew"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("500 0 100\n0 510 80\n0 0 2", "k"); }), "k:3:"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("-5 0 100\n0 510 80\n0 0 1", "k"); }), "positive"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("500 0 100\n0 510 80", "k"); }), "got 2"));
  // Issue 35: finite but absurd focal lengths are refused at their line (640 px: 27.968..73344 px).
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("1e300 0 320\n0 585 240\n0 0 1", "k"); }),
                       "k:1: expected fx within 27.968..73344 px"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_seven_scenes_intrinsics("585 0 320\n0 1e-300 240\n0 0 1", "k"); }),
                       "k:2: expected fy within"));
}

namespace {

// Three frames 0, 1, 3 (numbers need not be consecutive) at 8x6 with a camera file; frame 1 is JPEG colour.
struct SevenScenesFolder {
  TempDir dir{"7scenes"};
  hf::DatasetOptions options;
  SevenScenesFolder() {
    for (int n : {3, 0, 1}) {
      const std::string stem = dir / ("frame-00000" + std::to_string(n));
      cv::Mat raw(6, 8, CV_16UC1, cv::Scalar(1000 + 100 * n));
      raw.at<std::uint16_t>(0, 0) = 65535;
      raw.at<std::uint16_t>(0, 1) = 0;
      EXPECT_TRUE(cv::imwrite(stem + ".depth.png", raw));
      EXPECT_TRUE(cv::imwrite(stem + (n == 1 ? ".color.jpg" : ".color.png"), cv::Mat(6, 8, CV_8UC3, cv::Scalar(0, 0, 200))));
      write_text(stem + ".pose.txt", translation_pose(0.1 * n));
    }
    write_text(dir / "notes.txt", "not a frame\n");
    write_text(dir / "frame-x.depth.png", "not a frame either\n");
    hf::test::tiny_camera().save(dir / "cam.json");
    options.camera = dir / "cam.json";
  }
};

}  // namespace

TEST(SevenScenesDataset, ReadsFramesInOrder) {
  SevenScenesFolder folder;
  hf::SevenScenesDataset data(folder.dir.str(), folder.options);
  ASSERT_EQ(data.size(), 3u);
  EXPECT_EQ(data.camera(), hf::test::tiny_camera());
  EXPECT_TRUE(contains(data.camera_origin(), "--camera"));
  ASSERT_EQ(data.ground_truth().size(), 3u);
  const int numbers[] = {0, 1, 3};
  for (int k = 0; k < 3; ++k) {
    const hf::FrameRead r = data.next();
    ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
    const int n = numbers[k];
    EXPECT_EQ(r.frame.index, size_t(k));
    EXPECT_DOUBLE_EQ(r.frame.timestamp_s, n / 30.0);
    EXPECT_EQ(r.frame.depth(0, 0), 0.0f);  // 65535 = invalid
    EXPECT_EQ(r.frame.depth(1, 0), 0.0f);
    EXPECT_FLOAT_EQ(r.frame.depth(4, 3), (1000 + 100 * n) / 1000.0f);  // millimetres
    EXPECT_NEAR(r.frame.color(2, 2).r, 200, n == 1 ? 6 : 0);
    EXPECT_EQ(r.frame.color(2, 2).b, 0);
    ASSERT_TRUE(r.frame.T_world_camera_gt);
    EXPECT_NEAR(r.frame.T_world_camera_gt->translation().x(), 0.1 * n, 1e-9);
    EXPECT_DOUBLE_EQ(data.ground_truth()[size_t(k)].timestamp_s, n / 30.0);
  }
  EXPECT_EQ(data.next().status, hf::FrameStatus::end);
}

TEST(SevenScenesDataset, MissingFilesAndBadPoses) {
  SevenScenesFolder folder;
  std::filesystem::remove(folder.dir / "frame-000001.color.jpg");
  std::filesystem::remove(folder.dir / "frame-000003.pose.txt");
  hf::test::truncate_file(folder.dir / "frame-000000.depth.png");
  hf::SevenScenesDataset data(folder.dir.str(), folder.options);
  EXPECT_EQ(data.ground_truth().size(), 2u);
  const hf::FrameRead truncated = data.next();
  EXPECT_EQ(truncated.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(truncated.message, "frame-000000.depth.png")) << truncated.message;
  const hf::FrameRead no_colour = data.next();
  EXPECT_EQ(no_colour.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(no_colour.message, "frame-000001.color")) << no_colour.message;
  const hf::FrameRead no_pose = data.next();
  ASSERT_EQ(no_pose.status, hf::FrameStatus::ok) << no_pose.message;
  EXPECT_FALSE(no_pose.frame.T_world_camera_gt);

  write_text(folder.dir / "frame-000003.pose.txt", "1 0 0\n");
  EXPECT_TRUE(contains(error_of([&] { hf::SevenScenesDataset d(folder.dir.str(), folder.options); }),
                       "frame-000003.pose.txt:1: expected 4 numbers"));
}

TEST(SevenScenesDataset, CameraFromIntrinsicsFileOrPreset) {
  TempDir dir("7scenes_cam");
  cv::imwrite(dir / "frame-000000.depth.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(1500)));
  cv::imwrite(dir / "frame-000000.color.png", cv::Mat(480, 640, CV_8UC3, cv::Scalar(1, 2, 3)));
  {
    hf::SevenScenesDataset data(dir.str());
    EXPECT_EQ(data.camera(), hf::PinholeCamera::preset("7scenes"));
    EXPECT_TRUE(contains(data.camera_origin(), "preset 7scenes")) << data.camera_origin();
    EXPECT_TRUE(data.ground_truth().empty());
  }
  write_text(dir / "camera-intrinsics.txt", "500 0 321\n0 501 241\n0 0 1\n");
  hf::SevenScenesDataset data(dir.str());
  EXPECT_EQ(data.camera().fx, 500.0);
  EXPECT_EQ(data.camera().cy, 241.0);
  EXPECT_EQ(data.camera().width, 640);
  EXPECT_TRUE(contains(data.camera_origin(), "camera-intrinsics.txt")) << data.camera_origin();
  const hf::FrameRead r = data.next();
  ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
  EXPECT_FLOAT_EQ(r.frame.depth(320, 240), 1.5f);
  EXPECT_EQ(r.frame.color(0, 0), (hf::Rgb8{3, 2, 1}));
}
