// io/dataset: camera choice and its reason, format detection, open_dataset errors and prefetching.
#include "io/dataset.h"

#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"
#include "io/prefetch.h"
#include "tests/io/test_dataset_util.h"

using hf::test::contains;
using hf::test::error_of;
using hf::test::TempDir;
using hf::test::write_text;

TEST(DatasetCamera, PresetFromFolderName) {
  EXPECT_EQ(hf::preset_from_folder_name("/data/rgbd_dataset_freiburg1_desk"), "fr1");
  EXPECT_EQ(hf::preset_from_folder_name("/data/rgbd_dataset_freiburg2_xyz/"), "fr2");
  EXPECT_EQ(hf::preset_from_folder_name("data/tum_fr1_rpy_first150"), "fr1");
  EXPECT_EQ(hf::preset_from_folder_name("FR3-long-office"), "fr3");
  EXPECT_EQ(hf::preset_from_folder_name("/data/fr2/desk"), "");    // only the folder's own name counts
  EXPECT_EQ(hf::preset_from_folder_name("/data/xfr12_scan"), "");  // not a separate word
  EXPECT_EQ(hf::preset_from_folder_name("/data/freiburg4"), "");
  EXPECT_EQ(hf::preset_from_folder_name("/data/living_room"), "");
}

TEST(DatasetCamera, TumRulesInOrderWithTheirReasons) {
  TempDir root("camera");
  const std::string folder = root / "rgbd_dataset_freiburg2_pioneer";
  std::filesystem::create_directories(folder);

  // fr2 (and fr1): distorted images with pre-registered depth -> the ROS defaults, with the reason.
  hf::CameraChoice c = hf::choose_tum_camera(folder, "");
  EXPECT_EQ(c.camera, hf::PinholeCamera::preset("ros"));
  EXPECT_TRUE(contains(c.origin, "folder name 'rgbd_dataset_freiburg2_pioneer' is TUM fr2")) << c.origin;
  {
    const std::string fr3 = root / "rgbd_dataset_freiburg3_office";
    std::filesystem::create_directories(fr3);
    const hf::CameraChoice c3 = hf::choose_tum_camera(fr3, "");
    EXPECT_EQ(c3.camera, hf::PinholeCamera::preset("fr3"));
    EXPECT_TRUE(contains(c3.origin, "preset fr3 (folder name 'rgbd_dataset_freiburg3_office')")) << c3.origin;
  }

  write_text(folder + "/camera.txt", "fx 100\nfy 101\ncx 50\ncy 40\nwidth 100\nheight 80\n");
  c = hf::choose_tum_camera(folder, "");
  EXPECT_EQ(c.camera.fx, 100.0);
  EXPECT_TRUE(contains(c.origin, "camera.txt")) << c.origin;

  hf::test::tiny_camera().save(folder + "/camera.json");  // camera.json wins over camera.txt
  c = hf::choose_tum_camera(folder, "");
  EXPECT_EQ(c.camera, hf::test::tiny_camera());
  EXPECT_TRUE(contains(c.origin, "camera.json")) << c.origin;

  c = hf::choose_tum_camera(folder, "fr3");  // --camera wins over everything
  EXPECT_EQ(c.camera, hf::PinholeCamera::preset("fr3"));
  EXPECT_TRUE(contains(c.origin, "preset fr3 (--camera)")) << c.origin;
  c = hf::choose_tum_camera(folder, folder + "/camera.txt");
  EXPECT_EQ(c.camera.fx, 100.0);
  EXPECT_TRUE(contains(c.origin, "(--camera)")) << c.origin;
  const std::string bad = hf::test::error_of([&] { hf::choose_tum_camera(folder, "fr9"); });
  EXPECT_TRUE(contains(bad, "'fr9'") && contains(bad, "fr1")) << bad;

  write_text(folder + "/camera.json", "{\"fx\": 1,\n \"fy\": }");  // malformed file: its line
  EXPECT_TRUE(contains(error_of([&] { hf::choose_tum_camera(folder, ""); }), "camera.json:2:"));

  const std::string plain = root / "my_scan";
  std::filesystem::create_directories(plain);
  c = hf::choose_tum_camera(plain, "");
  EXPECT_EQ(c.camera, hf::PinholeCamera::preset("ros"));
  EXPECT_TRUE(contains(c.origin, "preset ros (default")) << c.origin;
}

TEST(DatasetDetect, FormatsAndErrorsNameThePath) {
  TempDir root("detect");
  const std::string missing = root / "missing";
  EXPECT_EQ(hf::detect_dataset_format(missing), hf::DatasetFormat::unknown);
  EXPECT_TRUE(contains(error_of([&] { hf::open_dataset(missing); }), missing + ": dataset folder not found"));

  write_text(root / "file.txt", "x");
  EXPECT_TRUE(contains(error_of([&] { hf::open_dataset(root / "file.txt"); }), "expected a dataset folder"));

  const std::string empty = root / "empty";
  std::filesystem::create_directories(empty);
  const std::string unknown = error_of([&] { hf::open_dataset(empty); });
  EXPECT_TRUE(contains(unknown, empty + ": unknown dataset layout")) << unknown;

  // TUM lists that associate nothing.
  const std::string tum = root / "tum";
  write_text(tum + "/rgb.txt", "1.0 rgb/a.png\n");
  write_text(tum + "/depth.txt", "2.0 depth/a.png\n");
  EXPECT_EQ(hf::detect_dataset_format(tum), hf::DatasetFormat::tum);
  const std::string none = error_of([&] { hf::open_dataset(tum); });
  EXPECT_TRUE(contains(none, tum + ": dataset has no frames (1 colour and 1 depth entries")) << none;
  write_text(tum + "/rgb.txt", "");
  write_text(tum + "/depth.txt", "");
  EXPECT_TRUE(contains(error_of([&] { hf::open_dataset(tum); }), "has no frames"));

  const std::string seven = root / "seven";
  std::filesystem::create_directories(seven);
  write_text(seven + "/frame-000000.pose.txt", "1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n");
  EXPECT_EQ(hf::detect_dataset_format(seven), hf::DatasetFormat::unknown);  // a pose alone is not a frame
  ASSERT_TRUE(cv::imwrite(seven + "/frame-000000.depth.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(900))));
  EXPECT_EQ(hf::detect_dataset_format(seven), hf::DatasetFormat::seven_scenes);
}

TEST(DatasetOpen, OpensBothFormatsWithAndWithoutPrefetch) {
  TempDir root("open");
  // TUM folder of 3 frames.
  const std::string tum = root / "rgbd_dataset_freiburg1_tiny";
  std::string rgb, depth;
  for (int i = 0; i < 3; ++i) {
    const std::string n = std::to_string(i);
    hf::test::write_frame_images(tum + "/depth/" + n + ".png", tum + "/rgb/" + n + ".png", 640, 480, 1.0f + 0.1f * i,
                                 std::uint8_t(i));
    rgb += std::to_string(100.0 + i / 30.0) + " rgb/" + n + ".png\n";
    depth += std::to_string(100.001 + i / 30.0) + " depth/" + n + ".png\n";
  }
  write_text(tum + "/rgb.txt", rgb);
  write_text(tum + "/depth.txt", depth);

  for (size_t prefetch : {size_t(0), size_t(2)}) {
    hf::DatasetOptions options;
    options.prefetch_frames = prefetch;
    std::unique_ptr<hf::FrameSource> source = hf::open_dataset(tum, options);
    EXPECT_EQ(dynamic_cast<hf::PrefetchingSource*>(source.get()) != nullptr, prefetch > 0);
    EXPECT_EQ(source->size(), 3u);
    // fr1 in the name: the pinhole measured on fr1 (distorted images, pre-registered depth; see io/dataset.h),
    // said why.
    EXPECT_EQ(source->camera(), hf::PinholeCamera::preset("fr1-registered"));
    EXPECT_TRUE(contains(source->camera_origin(), "preset fr1-registered (folder name")) << source->camera_origin();
    EXPECT_TRUE(contains(source->camera_origin(), "is TUM fr1")) << source->camera_origin();
    EXPECT_TRUE(contains(source->name(), "TUM RGB-D"));
    for (size_t i = 0; i < 3; ++i) {
      const hf::FrameRead r = source->next();
      ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
      EXPECT_EQ(r.frame.index, i);
      EXPECT_EQ(r.frame.color(0, 0).r, i);
      EXPECT_NEAR(r.frame.depth(10, 10), 1.0 + 0.1 * double(i), 1e-4);
    }
    EXPECT_EQ(source->next().status, hf::FrameStatus::end);
  }
  // Stopping early: destroying a prefetching source mid-sequence joins its thread.
  {
    auto source = hf::open_dataset(tum);
    EXPECT_EQ(source->next().status, hf::FrameStatus::ok);
  }

  const std::string seven = root / "seven";
  std::filesystem::create_directories(seven);
  ASSERT_TRUE(cv::imwrite(seven + "/frame-000000.depth.png", cv::Mat(480, 640, CV_16UC1, cv::Scalar(900))));
  ASSERT_TRUE(cv::imwrite(seven + "/frame-000000.color.jpg", cv::Mat(480, 640, CV_8UC3, cv::Scalar(9, 9, 9))));
  auto source = hf::open_dataset(seven);
  EXPECT_TRUE(contains(source->name(), "7-Scenes"));
  const hf::FrameRead r = source->next();
  ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
  EXPECT_FLOAT_EQ(r.frame.depth(0, 0), 0.9f);
  EXPECT_EQ(source->next().status, hf::FrameStatus::end);
}
