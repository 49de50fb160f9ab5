// TUM RGB-D reader: list parsing, ground-truth interpolation, association, decoding and per-frame failures.
#include "io/tum_dataset.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <sstream>

#include "core/error.h"
#include "tests/io/test_dataset_util.h"

using hf::test::contains;
using hf::test::error_of;
using hf::test::TempDir;
using hf::test::write_text;

namespace {

// Throws a ParseError and returns it, or fails the test.
hf::ParseError parse_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const hf::ParseError& e) {
    return e;
  }
  ADD_FAILURE() << "expected hf::ParseError";
  return hf::ParseError("none", 0, "none");
}

}  // namespace

TEST(TumList, CommentsBlankLinesAnyWhitespaceAndSorting) {
  const std::string text =
      "# color images\n"
      "# timestamp filename\n"
      "\n"
      "1305031229.564425\trgb/b.png\r\n"
      "   \t  \n"
      "  1305031229.528748   rgb/a.png  \n"
      "1305031229.596,rgb/c.png\n";  // associate.py also splits on commas
  const auto entries = hf::parse_tum_list(text, "rgb.txt");
  ASSERT_EQ(entries.size(), 3u);
  EXPECT_DOUBLE_EQ(entries[0].timestamp_s, 1305031229.528748);
  EXPECT_EQ(entries[0].file, "rgb/a.png");
  EXPECT_EQ(entries[0].line, 6);
  EXPECT_EQ(entries[1].file, "rgb/b.png");  // no '\r' left in the name
  EXPECT_EQ(entries[1].line, 4);
  EXPECT_EQ(entries[2].file, "rgb/c.png");
  EXPECT_TRUE(hf::parse_tum_list("", "empty.txt").empty());
  EXPECT_TRUE(hf::parse_tum_list("# only a comment", "c.txt").empty());
}

TEST(TumList, MalformedLinesNameFileAndLine) {
  struct Case {
    std::string text;
    int line;
    std::string expect;
  };
  const Case cases[] = {
      {"1.0 a.png\n2.0\n", 2, "expected 'timestamp filename'"},
      {"1.0 a.png extra\n", 1, "expected 'timestamp filename'"},
      {"# c\nabc a.png\n", 2, "time stamp"},
      {"1.0x a.png\n", 1, "time stamp"},
      {"nan a.png\n", 1, "time stamp"},
      {"inf a.png\n", 1, "time stamp"},
      {"1.0 a.png\n2.0 b.png\n1.0 c.png\n", 3, "line 1 again"},
  };
  for (const Case& c : cases) {
    const hf::ParseError e = parse_error_of([&] { hf::parse_tum_list(c.text, "dir/rgb.txt"); });
    EXPECT_EQ(e.line(), c.line) << c.text;
    EXPECT_TRUE(contains(e.what(), "dir/rgb.txt:" + std::to_string(c.line) + ": ")) << e.what();
    EXPECT_TRUE(contains(e.what(), c.expect)) << e.what();
  }
}

TEST(TumGroundTruthLookup, ExactMidpointPose) {
  // Pure translation: the geodesic midpoint is the arithmetic one.
  hf::Trajectory line = {{10.0, hf::SE3()}, {10.01, hf::SE3(Eigen::Quaterniond::Identity(), {0.2, -0.4, 1.0})}};
  const auto mid = hf::interpolate_pose(line, 10.005, 0.02);
  ASSERT_TRUE(mid);
  EXPECT_NEAR((mid->translation() - Eigen::Vector3d(0.1, -0.2, 0.5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(mid->angle_rad(), 0.0, 1e-12);

  // A screw motion: the midpoint M splits a -> b into two equal halves (a^-1 M == M^-1 b), each of half the angle.
  const hf::SE3 a(Eigen::Quaterniond(Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized())), {1, 2, 3});
  const hf::SE3 b = a * hf::SE3(Eigen::Quaterniond(Eigen::AngleAxisd(0.4, Eigen::Vector3d::UnitZ())), {0.3, 0.1, 0.0});
  const hf::Trajectory screw = {{0.0, a}, {0.01, b}};
  const auto m = hf::interpolate_pose(screw, 0.005, 0.02);
  ASSERT_TRUE(m);
  const hf::SE3 first = a.inverse() * *m, second = m->inverse() * b;
  EXPECT_NEAR((first.matrix() - second.matrix()).cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_NEAR(first.angle_rad(), 0.2, 1e-12);

  // At a sample's own stamp: that sample.
  const auto at_b = hf::interpolate_pose(screw, 0.01, 0.02);
  ASSERT_TRUE(at_b);
  EXPECT_NEAR((at_b->matrix() - b.matrix()).cwiseAbs().maxCoeff(), 0.0, 1e-12);
}

TEST(TumGroundTruthLookup, AbsentWhenNoSampleWithinTolerance) {
  const hf::Trajectory gt = {{0.0, hf::SE3()}, {1.0, hf::SE3(Eigen::Quaterniond::Identity(), {1, 0, 0})}};
  EXPECT_FALSE(hf::interpolate_pose(gt, 0.5, 0.02));   // a gap in the motion capture
  ASSERT_TRUE(hf::interpolate_pose(gt, 0.015, 0.02));  // near the first sample: interpolated
  EXPECT_NEAR(hf::interpolate_pose(gt, 0.015, 0.02)->translation().x(), 0.015, 1e-12);
  ASSERT_TRUE(hf::interpolate_pose(gt, 0.985, 0.02));
  // Before the first / after the last sample: the end sample, never extrapolated, only within the tolerance.
  ASSERT_TRUE(hf::interpolate_pose(gt, -0.01, 0.02));
  EXPECT_EQ(hf::interpolate_pose(gt, -0.01, 0.02)->translation().x(), 0.0);
  EXPECT_FALSE(hf::interpolate_pose(gt, -0.03, 0.02));
  ASSERT_TRUE(hf::interpolate_pose(gt, 1.019, 0.02));
  EXPECT_EQ(hf::interpolate_pose(gt, 1.019, 0.02)->translation().x(), 1.0);
  EXPECT_FALSE(hf::interpolate_pose(gt, 1.021, 0.02));
  EXPECT_FALSE(hf::interpolate_pose({}, 0.0, 0.02));
  EXPECT_NEAR(hf::nearest_sample_distance(gt, 0.3), 0.3, 1e-15);
  EXPECT_NEAR(hf::nearest_sample_distance(gt, 1.5), 0.5, 1e-15);
  EXPECT_TRUE(std::isinf(hf::nearest_sample_distance({}, 0.0)));
}

namespace {

constexpr int kW = 8, kH = 6;

// Five colour frames at 30 Hz from t = 1000 s, depth frames jittered by a few ms, ground truth at 100 Hz from
// 999.95 s to 1000.10 s moving along x at 1 m/s (so the last colour frame, 1000.1333 s, is 33 ms past it).
struct TumFolder {
  TempDir dir{"tum"};
  std::vector<double> rgb_stamps = {1000.0, 1000.0333, 1000.0667, 1000.1, 1000.1333};
  std::vector<double> depth_jitter = {0.004, -0.006, 0.0, 0.011, -0.002};

  explicit TumFolder(bool with_gt = true, bool with_camera = true) {
    std::ostringstream rgb, depth, gt;
    rgb.precision(17);
    depth.precision(17);
    gt.precision(17);
    rgb << "# color images\n# timestamp filename\n";
    depth << "# depth maps\n";
    for (size_t i = 0; i < rgb_stamps.size(); ++i) {
      const std::string n = std::to_string(i);
      rgb << rgb_stamps[i] << " rgb/" << n << ".png\n";
      depth << rgb_stamps[i] + depth_jitter[i] << "\tdepth/" << n << ".png\n";
      hf::test::write_frame_images(dir / ("depth/" + n + ".png"), dir / ("rgb/" + n + ".png"), kW, kH,
                                   1.0f + 0.5f * float(i), std::uint8_t(10 * i));
    }
    write_text(dir / "rgb.txt", rgb.str());
    write_text(dir / "depth.txt", depth.str());
    if (with_gt) {
      gt << "# ground truth\n";
      for (int k = 0; k <= 15; ++k) {
        const double t = 999.95 + 0.01 * k;
        gt << t << " " << (t - 1000.0) << " 0 0 0 0 0 1\n";
      }
      write_text(dir / "groundtruth.txt", gt.str());
    }
    if (with_camera) hf::test::tiny_camera(kW, kH).save(dir / "camera.json");
  }
};

}  // namespace

TEST(TumDataset, ReadsAssociatesAndInterpolates) {
  TumFolder folder;
  hf::TumDataset data(folder.dir.str());
  EXPECT_EQ(data.size(), 5u);
  EXPECT_EQ(data.camera(), hf::test::tiny_camera(kW, kH));
  EXPECT_TRUE(contains(data.camera_origin(), "camera.json")) << data.camera_origin();
  EXPECT_TRUE(contains(data.name(), folder.dir.str()));
  EXPECT_EQ(data.ground_truth().size(), 16u);
  const hf::TumSummary& s = data.summary();
  EXPECT_EQ(s.rgb_entries, 5u);
  EXPECT_EQ(s.depth_entries, 5u);
  EXPECT_EQ(s.frames, 5u);
  EXPECT_EQ(s.frames_with_gt, 4u);
  EXPECT_NEAR(s.max_rgb_depth_difference_s, 0.011, 1e-9);

  for (size_t i = 0; i < 5; ++i) {
    const hf::FrameRead r = data.next();
    ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
    const hf::RgbdFrame& f = r.frame;
    EXPECT_EQ(f.index, i);
    EXPECT_DOUBLE_EQ(f.timestamp_s, folder.rgb_stamps[i]);
    EXPECT_TRUE(contains(f.color_file, "rgb/" + std::to_string(i) + ".png"));
    EXPECT_TRUE(contains(f.depth_file, "depth/" + std::to_string(i) + ".png"));
    ASSERT_EQ(f.depth.width(), kW);
    ASSERT_EQ(f.color.height(), kH);
    EXPECT_FLOAT_EQ(f.depth(3, 2), 1.0f + 0.5f * float(i));  // 5000 units per metre, exact for these values
    EXPECT_EQ(f.color(5, 4), (hf::Rgb8{std::uint8_t(10 * i), 5, 4}));
    if (i < 4) {
      ASSERT_TRUE(f.T_world_camera_gt);
      // Linear motion: interpolation is exact up to the text precision of the stamps.
      EXPECT_NEAR(f.T_world_camera_gt->translation().x(), f.timestamp_s - 1000.0, 1e-9);
    } else {
      EXPECT_FALSE(f.T_world_camera_gt);  // 33 ms after the last ground-truth sample
    }
  }
  EXPECT_EQ(data.next().status, hf::FrameStatus::end);
  EXPECT_EQ(data.next().status, hf::FrameStatus::end);
}

TEST(TumDataset, MissingGroundTruthIsFine) {
  TumFolder folder(/*with_gt=*/false);
  hf::TumDataset data(folder.dir.str());
  EXPECT_TRUE(data.ground_truth().empty());
  EXPECT_EQ(data.summary().frames_with_gt, 0u);
  const hf::FrameRead r = data.next();
  ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
  EXPECT_FALSE(r.frame.T_world_camera_gt);
}

TEST(TumDataset, AssociationOptionsAndDepthScale) {
  TumFolder folder;
  hf::DatasetOptions tight;
  tight.association.max_difference_s = 0.005;  // drops the pairs 6 ms and 11 ms apart
  EXPECT_EQ(hf::TumDataset(folder.dir.str(), tight).size(), 3u);

  // An offset that moves every depth stamp by +0.5 s leaves nothing within 20 ms ...
  hf::DatasetOptions offset;
  offset.association.offset_s = 0.5;
  EXPECT_EQ(hf::TumDataset(folder.dir.str(), offset).size(), 0u);
  // ... and rewriting the depth list 0.5 s early with that offset restores all five pairs.
  std::ostringstream depth;
  depth.precision(17);
  for (size_t i = 0; i < 5; ++i)
    depth << folder.rgb_stamps[i] + folder.depth_jitter[i] - 0.5 << " depth/" << i << ".png\n";
  write_text(folder.dir / "depth.txt", depth.str());
  hf::TumDataset shifted(folder.dir.str(), offset);
  EXPECT_EQ(shifted.size(), 5u);
  EXPECT_NEAR(shifted.summary().max_rgb_depth_difference_s, 0.011, 1e-6);

  hf::DatasetOptions mm;
  mm.depth_scale = 1000.0;
  mm.association = offset.association;
  hf::TumDataset data(folder.dir.str(), mm);
  const hf::FrameRead r = data.next();
  ASSERT_EQ(r.status, hf::FrameStatus::ok) << r.message;
  EXPECT_FLOAT_EQ(r.frame.depth(0, 0), 5.0f);  // raw 5000 read as millimetres
}

TEST(TumDataset, BadImagesAreBadFramesNotExceptions) {
  TumFolder folder;
  std::filesystem::remove(folder.dir / "depth/1.png");
  hf::test::truncate_file(folder.dir / "rgb/2.png");
  // Wrong size: frame 3 at 4x6 in both images; frame 4 depth 8x6 but colour 4x6.
  hf::write_depth_png(folder.dir / "depth/3.png", hf::DepthImage(4, kH, 1.0f));
  hf::write_color_png(folder.dir / "rgb/3.png", hf::ColorImage(4, kH));
  hf::write_color_png(folder.dir / "rgb/4.png", hf::ColorImage(4, kH));

  hf::TumDataset data(folder.dir.str());
  ASSERT_EQ(data.size(), 5u);
  EXPECT_EQ(data.next().status, hf::FrameStatus::ok);

  const hf::FrameRead missing = data.next();
  EXPECT_EQ(missing.status, hf::FrameStatus::bad_frame);
  EXPECT_EQ(missing.frame.index, 1u);
  EXPECT_TRUE(contains(missing.message, "depth/1.png")) << missing.message;
  EXPECT_EQ(missing.message.find('\n'), std::string::npos);
  EXPECT_TRUE(missing.frame.depth.empty());

  const hf::FrameRead truncated = data.next();
  EXPECT_EQ(truncated.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(truncated.message, "rgb/2.png")) << truncated.message;

  const hf::FrameRead small = data.next();
  EXPECT_EQ(small.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(small.message, "4x6")) << small.message;
  EXPECT_TRUE(contains(small.message, "camera is 8x6")) << small.message;

  const hf::FrameRead mismatch = data.next();
  EXPECT_EQ(mismatch.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(mismatch.message, "rgb/4.png")) << mismatch.message;
  EXPECT_TRUE(contains(mismatch.message, "8x6")) << mismatch.message;

  EXPECT_EQ(data.next().status, hf::FrameStatus::end);
  // read(i) decodes without moving the cursor and reports an index out of range as a bad frame.
  EXPECT_EQ(data.read(0).status, hf::FrameStatus::ok);
  EXPECT_EQ(data.read(99).status, hf::FrameStatus::bad_frame);
}

TEST(TumDataset, FolderLevelErrorsThrow) {
  TumFolder folder;
  // A malformed list line: ParseError naming the file and line.
  write_text(folder.dir / "rgb.txt", "# header\n1000.0 rgb/0.png\n1000.1 rgb/1.png what\n");
  const std::string bad_list = error_of([&] { hf::TumDataset d(folder.dir.str()); });
  EXPECT_TRUE(contains(bad_list, "rgb.txt:3: expected")) << bad_list;

  // A malformed ground-truth line.
  TumFolder folder2;
  write_text(folder2.dir / "groundtruth.txt", "1.0 0 0 0 0 0 0 1\n2.0 0 0 0 0 0 1\n");
  const std::string bad_gt = error_of([&] { hf::TumDataset d(folder2.dir.str()); });
  EXPECT_TRUE(contains(bad_gt, "groundtruth.txt:2:")) << bad_gt;

  // Missing lists and folders.
  TumFolder folder3;
  std::filesystem::remove(folder3.dir / "depth.txt");
  EXPECT_TRUE(contains(error_of([&] { hf::TumDataset d(folder3.dir.str()); }), "depth.txt"));
  const std::string none = folder3.dir / "nope";
  EXPECT_TRUE(contains(error_of([&] { hf::TumDataset d(none); }), none));

  // Invalid options.
  hf::DatasetOptions bad;
  bad.association.max_difference_s = 0.0;
  EXPECT_FALSE(error_of([&] { hf::TumDataset d(folder.dir.str(), bad); }).empty());
  bad = {};
  bad.depth_scale = -1.0;
  EXPECT_FALSE(error_of([&] { hf::TumDataset d(folder.dir.str(), bad); }).empty());
  bad = {};
  bad.camera = "no-such-preset-or-file";
  TumFolder folder4;
  EXPECT_TRUE(contains(error_of([&] { hf::TumDataset d(folder4.dir.str(), bad); }), "no-such-preset-or-file"));
}

// Issue 14.7: a groundtruth.txt linked to /dev/zero was read until memory ran out; an rgb.txt FIFO blocked forever.
TEST(TumDataset, ListsThatAreNotRegularFilesAreRefusedAtOnce) {
  TumFolder zero;
  if (std::filesystem::exists("/dev/zero")) {
    std::filesystem::remove(zero.dir / "groundtruth.txt");
    std::filesystem::create_symlink("/dev/zero", zero.dir / "groundtruth.txt");
    const std::string e = error_of([&] { hf::TumDataset d(zero.dir.str()); });
    EXPECT_TRUE(contains(e, "groundtruth.txt: cannot read trajectory file: it is a character device")) << e;
  }
  TumFolder fifo;
  std::filesystem::remove(fifo.dir / "rgb.txt");
  ASSERT_EQ(::mkfifo((fifo.dir / "rgb.txt").c_str(), 0600), 0);
  const std::string e = error_of([&] { hf::TumDataset d(fifo.dir.str()); });
  EXPECT_TRUE(contains(e, "rgb.txt: cannot read image list: it is a FIFO")) << e;
}

// Issue 35.8: a symbolic link loop (or a link to nothing) named groundtruth.txt was read as "no ground truth" and
// the run went on without ATE; a folder there was already an error. Both now name the file.
TEST(TumDataset, GroundTruthLinkThatDoesNotResolveIsRefused) {
  TumFolder loop;
  const auto gt = loop.dir / "groundtruth.txt";
  std::filesystem::remove(gt);
  std::filesystem::create_symlink("groundtruth.txt", gt);  // itself: ELOOP
  const std::string e = error_of([&] { hf::TumDataset d(loop.dir.str()); });
  EXPECT_TRUE(contains(e, "groundtruth.txt: cannot read the ground truth (")) << e;
  TumFolder dangling;
  const auto gt2 = dangling.dir / "groundtruth.txt";
  std::filesystem::remove(gt2);
  std::filesystem::create_symlink("no_such_file.txt", gt2);
  const std::string e2 = error_of([&] { hf::TumDataset d(dangling.dir.str()); });
  EXPECT_TRUE(contains(e2, "groundtruth.txt: cannot read the ground truth (a link to nothing)")) << e2;
}

TEST(TumList, LongLinesAndTheirContentAreBounded) {
  // Built by append: gcc 12 warns falsely (-Warray-bounds) on "..." + std::string(n, c) + "..." once inlined here.
  std::string long_line = "1 a\n";
  long_line.append(5000, 'b').append("\n");
  const std::string msg = error_of([&] { hf::parse_tum_list(long_line, "rgb.txt"); });
  EXPECT_TRUE(contains(msg, "rgb.txt:2: expected a line of at most 4096 bytes")) << msg;
  const std::string esc = error_of([] { hf::parse_tum_list("1 a b \x1b]0;title\x07\n", "rgb.txt"); });
  EXPECT_TRUE(contains(esc, "rgb.txt:1: expected 'timestamp filename', got '1 a b ?]0;title?'")) << esc;
}

// Issue 14.10: a colour JPEG renamed .png was decoded, "tracked good" and fused. Content that contradicts the name
// is a bad frame naming the file and both formats.
TEST(TumDataset, ImageWhoseContentContradictsItsNameIsABadFrame) {
  TumFolder folder;
  const std::string jpeg = folder.dir / "rgb/2.jpg";
  ASSERT_TRUE(cv::imwrite(jpeg, cv::Mat(kH, kW, CV_8UC3, cv::Scalar(10, 20, 30))));
  std::filesystem::rename(jpeg, folder.dir / "rgb/2.png");
  hf::TumDataset data(folder.dir.str());
  const hf::FrameRead r = data.read(2);
  EXPECT_EQ(r.status, hf::FrameStatus::bad_frame);
  EXPECT_TRUE(contains(r.message, "rgb/2.png: colour image holds JPEG data but its name says PNG")) << r.message;
  EXPECT_EQ(data.read(1).status, hf::FrameStatus::ok);
}
