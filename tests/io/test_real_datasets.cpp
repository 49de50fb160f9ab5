// The readers on the real data in HF_SHARED_DIR/data: frame counts and association statistics as PROVENANCE.md
// there states them, and a few decoded frames. Only a few images are decoded per folder to keep this fast.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>

#include "io/dataset.h"
#include "io/prefetch.h"
#include "io/seven_scenes.h"
#include "io/tum_dataset.h"

namespace fs = std::filesystem;

namespace {

std::string data_dir() { return std::string(HF_SHARED_DIR) + "/data"; }

std::string require(const std::string& name) {
  const std::string path = data_dir() + "/" + name;
  return fs::is_directory(path) ? path : "";
}

#define REQUIRE_DATA(var, name)                                                                     \
  const std::string var = require(name);                                                            \
  if (var.empty()) GTEST_SKIP() << "real data '" << name << "' not found under " << data_dir()

void expect_plausible_frame(const hf::FrameRead& r, double min_depth_m, double max_depth_m) {
  ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
  ASSERT_EQ(r.frame.depth.width(), 640);
  ASSERT_EQ(r.frame.depth.height(), 480);
  ASSERT_EQ(r.frame.color.width(), 640);
  size_t valid = 0;
  float lo = 1e9f, hi = 0.0f;
  for (float d : r.frame.depth.pixels()) {
    if (d > 0.0f) {
      ++valid;
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
  }
  EXPECT_GT(valid, r.frame.depth.size() / 2) << r.frame.depth_file;
  EXPECT_GE(lo, min_depth_m) << r.frame.depth_file;
  EXPECT_LE(hi, max_depth_m) << r.frame.depth_file;
  long colour_sum = 0;
  for (const hf::Rgb8& c : r.frame.color.pixels()) colour_sum += c.r + c.g + c.b;
  EXPECT_GT(colour_sum, 0) << r.frame.color_file;
}

}  // namespace

TEST(RealData, TumFr1RpyFirst150) {
  REQUIRE_DATA(path, "tum_fr1_rpy_first150");
  hf::TumDataset data(path);
  const hf::TumSummary& s = data.summary();
  EXPECT_EQ(s.rgb_entries, 150u);
  EXPECT_EQ(s.depth_entries, 150u);
  EXPECT_EQ(s.groundtruth_poses, 2742u);
  EXPECT_EQ(s.frames, 150u);
  EXPECT_EQ(s.frames_with_gt, s.frames);  // "every rgb/depth timestamp has a groundtruth pose within 5 ms"
  EXPECT_LE(s.max_gt_distance_s, 0.005);
  EXPECT_LE(s.max_rgb_depth_difference_s, 0.0115);  // "rgb->nearest-depth association within 11.5 ms"
  EXPECT_EQ(data.camera(), hf::PinholeCamera::preset("fr1-registered"));  // fr1 from the folder name
  EXPECT_DOUBLE_EQ(data.frames().front().timestamp_s, 1305031229.528748);
  EXPECT_DOUBLE_EQ(data.frames().back().timestamp_s, 1305031234.493831);
  expect_plausible_frame(data.read(0), 0.3, 10.0);
  expect_plausible_frame(data.read(149), 0.3, 10.0);
  // Interpolated ground truth moves little between neighbouring frames (33 ms of hand-held motion).
  const hf::SE3 step = data.frames()[0].T_world_camera_gt->inverse() * *data.frames()[1].T_world_camera_gt;
  EXPECT_LT(step.translation().norm(), 0.05);
  EXPECT_LT(step.angle_rad(), 0.1);
}

TEST(RealData, TumFr1Desk9Frames) {
  REQUIRE_DATA(path, "tum_fr1_desk_9frames");
  hf::DatasetOptions options;
  options.prefetch_frames = 2;
  std::unique_ptr<hf::FrameSource> source = hf::open_dataset(path, options);
  EXPECT_EQ(source->size(), 9u);
  EXPECT_EQ(source->ground_truth().size(), 2335u);
  const auto* tum = dynamic_cast<const hf::TumDataset*>(&dynamic_cast<const hf::PrefetchingSource&>(*source).inner());
  ASSERT_NE(tum, nullptr);
  EXPECT_EQ(tum->summary().frames_with_gt, 9u);
  EXPECT_LE(tum->summary().max_gt_distance_s, 0.005);
  EXPECT_EQ(source->camera(), hf::PinholeCamera::preset("fr1-registered"));
  // Decode the first two through the prefetching wrapper, then stop early.
  for (size_t i = 0; i < 2; ++i) {
    const hf::FrameRead r = source->next();
    expect_plausible_frame(r, 0.3, 10.0);
    EXPECT_EQ(r.frame.index, i);
    EXPECT_TRUE(r.frame.T_world_camera_gt);
  }
}

TEST(RealData, SevenScenesFirst200) {
  REQUIRE_DATA(path, "7scenes_tsdf_fusion_first200");
  EXPECT_EQ(hf::detect_dataset_format(path), hf::DatasetFormat::seven_scenes);
  hf::SevenScenesDataset data(path);
  EXPECT_EQ(data.size(), 200u);
  EXPECT_EQ(data.ground_truth().size(), 200u);
  EXPECT_EQ(data.camera().fx, 585.0);
  EXPECT_EQ(data.camera().fy, 585.0);
  EXPECT_EQ(data.camera().cx, 320.0);
  EXPECT_EQ(data.camera().cy, 240.0);
  EXPECT_TRUE(data.camera_origin().find("camera-intrinsics.txt") != std::string::npos) << data.camera_origin();
  EXPECT_DOUBLE_EQ(data.frames().back().timestamp_s, 199.0 / 30.0);
  const hf::FrameRead r = data.read(0);
  expect_plausible_frame(r, 0.8, 3.5);
  // "frame 0: valid values 801..3493" millimetres.
  float lo = 1e9f, hi = 0.0f;
  for (float d : r.frame.depth.pixels())
    if (d > 0.0f) lo = std::min(lo, d), hi = std::max(hi, d);
  EXPECT_FLOAT_EQ(lo, 0.801f);
  EXPECT_FLOAT_EQ(hi, 3.493f);
  // Poses are continuous: "max inter-frame translation 3.6 cm", "path length 1.32 m".
  double path_m = 0.0, max_step_m = 0.0;
  for (size_t i = 1; i < data.ground_truth().size(); ++i) {
    const double step = (data.ground_truth()[i].T_world_camera.translation() -
                         data.ground_truth()[i - 1].T_world_camera.translation()).norm();
    path_m += step;
    max_step_m = std::max(max_step_m, step);
  }
  EXPECT_NEAR(path_m, 1.32, 0.01);
  EXPECT_NEAR(max_step_m, 0.036, 0.001);
}

TEST(RealData, EveryDatasetFolderOpens) {
  if (!fs::is_directory(data_dir())) GTEST_SKIP() << "no real data under " << data_dir();
  int opened = 0;
  for (const fs::directory_entry& entry : fs::directory_iterator(data_dir())) {
    if (!entry.is_directory() || hf::detect_dataset_format(entry.path().string()) == hf::DatasetFormat::unknown)
      continue;
    SCOPED_TRACE(entry.path().string());
    std::unique_ptr<hf::FrameSource> source = hf::open_dataset(entry.path().string());
    EXPECT_GT(source->size(), 0u);
    EXPECT_FALSE(source->camera_origin().empty());
    expect_plausible_frame(source->next(), 0.2, 20.0);
    ++opened;
  }
  EXPECT_GE(opened, 1);
  std::cout << "opened " << opened << " dataset folders under " << data_dir() << "\n";
}
