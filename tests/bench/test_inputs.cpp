// Input discovery for `hashfusion bench --input ...`, the method lists, and the speed/error plot.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "bench/harness/harness.h"
#include "bench/harness/inputs.h"
#include "bench/harness/speed_plot.h"
#include "core/error.h"
#include "datasets/presets.h"
#include "registration/registration.h"

namespace hf::bench {
namespace {
namespace fs = std::filesystem;

class BenchInputs : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("hf_bench_inputs_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
  }
  void TearDown() override { fs::remove_all(root_); }
  void touch(const fs::path& file) {
    fs::create_directories(file.parent_path());
    std::ofstream(file) << "# test\n";
  }
  fs::path root_;
};

TEST_F(BenchInputs, FindsDatasetsRecursivelyAndNotesOtherFolders) {
  touch(root_ / "tum_a" / "rgb.txt");
  touch(root_ / "tum_a" / "rgb" / "nested" / "depth.txt");  // inside a dataset: not searched
  touch(root_ / "scenes" / "seq-01" / "frame-000000.depth.png");
  touch(root_ / "scenes" / "seq-02" / "frame-000000.depth.png");
  fs::create_directories(root_ / "scenes" / "calibration");
  touch(root_ / "lidar" / "tiles" / "a.las");
  touch(root_ / ".cache" / "rgb.txt");  // hidden: ignored
  const DiscoveredInputs d = discover_inputs({root_.string()});
  ASSERT_EQ(d.inputs.size(), 3u);
  EXPECT_EQ(d.inputs[0].spec, (root_ / "scenes" / "seq-01").string());
  EXPECT_EQ(d.inputs[0].label, "seq-01");
  EXPECT_EQ(d.inputs[1].label, "seq-02");
  EXPECT_EQ(d.inputs[2].label, "tum_a");
  EXPECT_FALSE(d.inputs[2].synthetic);
  ASSERT_EQ(d.notes.size(), 2u);
  EXPECT_NE(d.notes[0].find((root_ / "lidar").string()), std::string::npos) << d.notes[0];
  EXPECT_NE(d.notes[1].find((root_ / "scenes" / "calibration").string()), std::string::npos) << d.notes[1];
  EXPECT_NE(d.notes[0].find("not a TUM or 7-Scenes dataset"), std::string::npos);
}

TEST_F(BenchInputs, DatasetFolderDirectlyAndDuplicatesOnce) {
  touch(root_ / "fr1" / "depth.txt");
  const DiscoveredInputs d =
      discover_inputs({(root_ / "fr1").string() + "/", root_.string(), (root_ / "." / "fr1").string()});
  ASSERT_EQ(d.inputs.size(), 1u);
  EXPECT_EQ(d.inputs[0].label, "fr1");
  EXPECT_TRUE(d.notes.empty());
}

TEST_F(BenchInputs, SameFolderNamesGetTheirParent) {
  touch(root_ / "a" / "x" / "rgb.txt");
  touch(root_ / "b" / "x" / "rgb.txt");
  const DiscoveredInputs d = discover_inputs({root_.string()});
  ASSERT_EQ(d.inputs.size(), 2u);
  EXPECT_EQ(d.inputs[0].label, "a/x");
  EXPECT_EQ(d.inputs[1].label, "b/x");
}

TEST_F(BenchInputs, ErrorsNameThePath) {
  fs::create_directories(root_ / "nothing" / "here");
  auto message = [](const std::vector<std::string>& in) {
    try {
      discover_inputs(in);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  const std::string none = (root_ / "nothing").string();
  EXPECT_NE(message({none}).find(none + ": no TUM RGB-D or 7-Scenes dataset"), std::string::npos);
  const std::string missing = (root_ / "missing").string();
  EXPECT_NE(message({missing}).find(missing + ": no such file or folder"), std::string::npos);
  touch(root_ / "file.txt");
  EXPECT_NE(message({(root_ / "file.txt").string()}).find("not a folder"), std::string::npos);
  EXPECT_NE(message({"synthetic:nope"}).find("unknown synthetic preset 'nope'"), std::string::npos);
}

TEST(BenchInputsSynthetic, AllPresetsAndSingleOnes) {
  const DiscoveredInputs d = discover_inputs({"synthetic:wall", "synthetic:all"});
  const std::vector<std::string> presets = datasets::preset_names();
  ASSERT_EQ(d.inputs.size(), presets.size());  // wall only once
  EXPECT_EQ(d.inputs[0].spec, "synthetic:wall");
  EXPECT_TRUE(d.inputs[0].synthetic);
  EXPECT_EQ(d.inputs[0].label, "synthetic:wall");
  for (const std::string& p : presets) {
    EXPECT_TRUE(std::any_of(d.inputs.begin(), d.inputs.end(),
                            [&](const BenchInput& in) { return in.spec == "synthetic:" + p; }))
        << p;
  }
}

TEST(BenchMethods, RegistrationsComeFromTheRegistry) {
  EXPECT_EQ(resolve_registrations("all"), registration_names());
  const std::string first = registration_names().front();
  EXPECT_EQ(resolve_registrations(first + ", groundtruth," + first),
            (std::vector<std::string>{first, "groundtruth"}));
  EXPECT_THROW(resolve_registrations("no-such-method"), Error);
  EXPECT_THROW(resolve_registrations(","), Error);
  EXPECT_TRUE(resolve_peers("none").empty());
  EXPECT_EQ(resolve_peers("all"), peer_names());
  EXPECT_THROW(resolve_peers("icp"), Error);
  EXPECT_EQ(resolve_loop_closure_modes("all"), (std::vector<std::string>{"off", "on", "global"}));
  EXPECT_EQ(resolve_loop_closure_modes("global,on"), (std::vector<std::string>{"global", "on"}));
  EXPECT_THROW(resolve_loop_closure_modes("sometimes"), Error);
  EXPECT_THROW(resolve_loop_closure_modes(""), Error);
  EXPECT_EQ(loop_closure_label("icp", "on"), "icp");
  EXPECT_EQ(loop_closure_label("icp", "off"), "icp -loops");
  EXPECT_EQ(loop_closure_label("icp", "global"), "icp +global");
  EXPECT_EQ(file_safe("synthetic:wall"), "synthetic_wall");
  EXPECT_EQ(file_safe("a/b c.d"), "a_b_c.d");
}

TEST(BenchSpeedPlot, DrawsPointsFrontAndLabels) {
  const std::vector<SpeedPoint> pts = {{"fast", 5.0, 0.08, false},
                                       {"slow", 200.0, 0.004, false},
                                       {"middle", 40.0, 0.02, false},
                                       {"dominated", 300.0, 0.09, true},
                                       {"nan", NAN, 0.1, false}};
  SpeedPlotOptions o;
  o.width_px = 640;
  o.height_px = 480;
  o.title = "test";
  const ColorImage img = render_speed_plot(pts, o);
  ASSERT_EQ(img.width(), 640);
  ASSERT_EQ(img.height(), 480);
  // The first palette colour (BGR 180,119,31 -> RGB 31,119,180) marks the first point.
  long coloured = 0;
  for (const Rgb8& p : img.pixels()) coloured += (p.r == 31 && p.g == 119 && p.b == 180) ? 1 : 0;
  EXPECT_GT(coloured, 20);
  EXPECT_NO_THROW(render_speed_plot({}, o));
  EXPECT_NO_THROW(render_speed_plot({{"one", 3.0, 0.0, false}}, o));
  // Issue 35: absurd but finite values are listed as not plotted instead of overflowing the axis ranges.
  EXPECT_NO_THROW(render_speed_plot(
      {{"one", 3.0, 0.01, false}, {"far", 1e308, 1e308, false}, {"tiny", 5e-324, 0.02, true}}, o));
  o.width_px = 100;
  EXPECT_THROW(render_speed_plot(pts, o), Error);

  // The footer fits the canvas (issue 36: it ran off the right edge): with a long "not plotted" list at the
  // smallest width, the text is wrapped, so the rightmost columns stay white, and the lines still show at the
  // bottom (dark text pixels in the lowest tenth).
  for (const int width : {400, 640, 1100}) {
    SpeedPlotOptions narrow = o;
    narrow.width_px = width;
    for (int k = 0; k < 30; ++k) narrow.not_plotted.push_back("method_number_" + std::to_string(k) + " (lost)");
    const ColorImage f = render_speed_plot(pts, narrow);
    long right_edge_ink = 0, footer_ink = 0;
    for (int y = 0; y < f.height(); ++y)
      for (int x = f.width() - 6; x < f.width(); ++x) right_edge_ink += f(x, y).r < 200 ? 1 : 0;
    for (int y = f.height() * 9 / 10; y < f.height(); ++y)
      for (int x = 0; x < f.width(); ++x) footer_ink += f(x, y).r < 200 ? 1 : 0;
    EXPECT_EQ(right_edge_ink, 0) << "text runs off the right edge at width " << width;
    EXPECT_GT(footer_ink, 50) << "no footer at width " << width;
  }

  const fs::path file = fs::temp_directory_path() / ("hf_speed_plot_" + std::to_string(::getpid()) + ".png");
  o.width_px = 640;
  write_speed_plot(file.string(), pts, o);
  EXPECT_GT(fs::file_size(file), 1000u);
  fs::remove(file);
}

}  // namespace
}  // namespace hf::bench
