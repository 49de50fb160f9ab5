// slam/eval_plot: the trajectory plot renders the data where the axes say it is, with the colour bar, and is
// written atomically as a PNG.
#include "slam/eval_plot.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "core/error.h"

namespace hf {
namespace {

Trajectory circle(double radius_m, double z_m) {
  Trajectory out;
  for (int k = 0; k <= 120; ++k) {
    const double t = k / 30.0, a = 2.0 * M_PI * k / 120.0;
    out.push_back(
        {t, SE3(Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ())),
                Eigen::Vector3d(radius_m * std::cos(a), radius_m * std::sin(a), z_m + 0.01 * std::sin(3 * a)))});
  }
  return out;
}

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / ("hf_eval_plot_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir;
}

TrajectoryPlotOptions sized(int width_px, int height_px) {
  TrajectoryPlotOptions options;
  options.width_px = width_px;
  options.height_px = height_px;
  return options;
}

int count_pixels(const ColorImage& img, bool (*pred)(const Rgb8&)) {
  int n = 0;
  for (const Rgb8& p : img.pixels()) n += pred(p) ? 1 : 0;
  return n;
}

TEST(TrajectoryPlot, DrawsGroundTruthEstimateAndColourBar) {
  const Trajectory gt = circle(1.0, 0.5);
  Trajectory est = circle(1.1, 0.5);  // 10 cm too large: ATE ~ 5 cm after alignment
  for (StampedPose& p : est)
    p.T_world_camera = SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(2, 0, 0)) * p.T_world_camera;
  const EvalResult r = evaluate_trajectory(gt, est);
  const ColorImage img = render_trajectory_plot(gt, est, r, sized(900, 700));
  ASSERT_EQ(img.width(), 900);
  ASSERT_EQ(img.height(), 700);
  // Black ground truth, and saturated viridis colours (the estimate and the colour bar) are present.
  EXPECT_GT(count_pixels(img, [](const Rgb8& p) { return p.r < 40 && p.g < 40 && p.b < 40; }), 2000);
  EXPECT_GT(count_pixels(img, [](const Rgb8& p) { return p.g > 150 && p.b < 100 && p.r > 150; }), 100);  // yellow
  EXPECT_GT(count_pixels(img, [](const Rgb8& p) { return p.b > 80 && p.r > 40 && p.r < 90 && p.g < 40; }),
            100);  // purple
  // The picture is mostly background.
  EXPECT_GT(count_pixels(img, [](const Rgb8& p) { return p.r == 255 && p.g == 255 && p.b == 255; }),
            img.width() * img.height() / 2);
}

// Issue 35: a pose at 1e308 m made the tick loops ("v <= hi; v += step" with hi = inf) spin forever. Positions
// beyond 1e9 m are refused with a message; far but plottable ones (5e8 m) still render, with a bounded tick count.
TEST(TrajectoryPlot, AbsurdRangesRefusedFarOnesRendered) {
  const Trajectory gt = circle(1.0, 0.0);
  const EvalResult r = evaluate_trajectory(gt, gt);
  for (const double far : {1e308, -1e10, double(NAN)}) {
    Trajectory bad = gt;
    bad[60].T_world_camera = SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(far, 0, 0));
    try {
      render_trajectory_plot(bad, gt, r);
      ADD_FAILURE() << "a position at " << far << " m was plotted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("beyond the 1e9 m a plot can show"), std::string::npos) << e.what();
    }
  }
  Trajectory shifted = gt;  // a 1 m circle 5e8 m from the origin: doubles still resolve 1e-7 m there
  for (StampedPose& p : shifted)
    p.T_world_camera = SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(5e8, 0, 0)) * p.T_world_camera;
  const EvalResult far = evaluate_trajectory(shifted, shifted);
  const ColorImage img = render_trajectory_plot(shifted, shifted, far, sized(900, 700));
  EXPECT_GT(count_pixels(img, [](const Rgb8& p) { return p.r < 40 && p.g < 40 && p.b < 40; }), 2000);
}

TEST(TrajectoryPlot, WritesAPngAtomicallyAndReportsBadPaths) {
  const Trajectory gt = circle(1.0, 0.0);
  const EvalResult r = evaluate_trajectory(gt, gt);  // zero error: the colour bar still has a range
  const auto dir = temp_dir();
  const std::string path = (dir / "plot.png").string();
  TrajectoryPlotOptions titled;
  titled.title = "self";
  write_trajectory_plot(path, gt, gt, r, titled);
  const cv::Mat back = cv::imread(path, cv::IMREAD_COLOR);
  EXPECT_EQ(back.cols, 1100);
  EXPECT_EQ(back.rows, 850);
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    EXPECT_EQ(entry.path().filename(), "plot.png") << "left a temporary behind";
  }
  EXPECT_THROW(write_trajectory_plot((dir / "missing" / "plot.png").string(), gt, gt, r), Error);
  // The plot is a PNG whatever the name says (io/image_io.h encodes PNG in memory; issue 14).
  write_trajectory_plot((dir / "plot.unknownext").string(), gt, gt, r);
  EXPECT_FALSE(cv::imread((dir / "plot.unknownext").string(), cv::IMREAD_COLOR).empty());
  EXPECT_THROW(render_trajectory_plot(gt, gt, r, sized(10, 700)), Error);
  TrajectoryPlotOptions bad_axis;
  bad_axis.drop_axis = 3;
  EXPECT_THROW(render_trajectory_plot(gt, gt, r, bad_axis), Error);
  EXPECT_THROW(render_trajectory_plot(Trajectory(gt.begin(), gt.begin() + 5), gt, r), Error);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace hf
