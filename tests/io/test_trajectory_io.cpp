// io/trajectory_io: TUM trajectory text, both directions.
#include "io/trajectory_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.h"
#include "tests/io/test_dataset_util.h"

using hf::test::contains;
using hf::test::error_of;

TEST(TrajectoryIo, ParsesCommentsWhitespaceAndQuaternionOrder) {
  const std::string text =
      "# ground truth trajectory\n"
      "# timestamp tx ty tz qx qy qz qw\n"
      "\n"
      "1305031225.9334 1.3357 0.6698 1.6180 0 0 0.70710678118654752 0.70710678118654752\r\n"
      "  1305031225.9434\t1 2 3\t0 0 0 2  \n";  // not normalised: scaled to unit length
  const hf::Trajectory t = hf::parse_tum_trajectory(text, "gt.txt");
  ASSERT_EQ(t.size(), 2u);
  EXPECT_DOUBLE_EQ(t[0].timestamp_s, 1305031225.9334);
  EXPECT_NEAR((t[0].T_world_camera.translation() - Eigen::Vector3d(1.3357, 0.6698, 1.6180)).norm(), 0.0, 1e-15);
  // qz = qw = sqrt(1/2) is 90 degrees about z: x maps to y.
  const Eigen::Vector3d x_rotated = t[0].T_world_camera.rotation() * Eigen::Vector3d::UnitX();
  EXPECT_NEAR((x_rotated - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  EXPECT_NEAR(t[1].T_world_camera.quaternion().w(), 1.0, 1e-15);
  EXPECT_TRUE(hf::parse_tum_trajectory("", "empty").empty());
}

TEST(TrajectoryIo, MalformedLinesNameFileAndLine) {
  struct Case {
    std::string text;
    int line;
    std::string expect;
  };
  const Case cases[] = {
      {"1 0 0 0 0 0 0 1\n2 0 0 0 0 0 1\n", 2, "expected 8 numbers"},
      {"1 0 0 0 0 0 0 1 9\n", 1, "got more"},
      {"# c\n1 0 0 zero 0 0 0 1\n", 2, "finite number"},
      {"1 0 0 nan 0 0 0 1\n", 1, "finite number"},
      {"1 0 0 0 0 0 0 inf\n", 1, "finite number"},
      {"1 0 0 0 0 0 0 0\n", 1, "non-zero quaternion"},
      {"1 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", 2, "strictly increasing"},
      {"2 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n", 2, "strictly increasing"},
  };
  for (const Case& c : cases) {
    const std::string msg = error_of([&] { hf::parse_tum_trajectory(c.text, "dir/gt.txt"); });
    EXPECT_TRUE(contains(msg, "dir/gt.txt:" + std::to_string(c.line) + ": ")) << c.text << " -> " << msg;
    EXPECT_TRUE(contains(msg, c.expect)) << msg;
  }
}

TEST(TrajectoryIo, ExtremeQuaternionsGiveUnitRotationsOrAnError) {
  // Components whose squares overflow double still describe a rotation (here 90 degrees about x); the norm
  // must not overflow into a zero, NaN-producing quaternion.
  const hf::Trajectory t = hf::parse_tum_trajectory("1 0 0 0 1e200 0 0 1e200\n", "q.txt");
  ASSERT_EQ(t.size(), 1u);
  EXPECT_TRUE(t[0].T_world_camera.is_finite());
  EXPECT_NEAR(t[0].T_world_camera.quaternion().norm(), 1.0, 1e-12);
  EXPECT_NEAR(t[0].T_world_camera.angle_rad(), M_PI / 2, 1e-12);
  // A quaternion of norm below 1e-6 is refused as zero, whatever its direction.
  EXPECT_TRUE(contains(error_of([] { hf::parse_tum_trajectory("1 0 0 0 0 0 1e-200 1e-200\n", "q.txt"); }),
                       "q.txt:1: expected a non-zero quaternion"));
}

TEST(TrajectoryIo, FormatParseRoundTripIsExact) {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  hf::Trajectory t;
  double stamp = 1305031229.528748;
  for (int i = 0; i < 50; ++i) {
    hf::Vector6d xi;
    for (int k = 0; k < 6; ++k) xi[k] = n(rng);
    t.push_back({stamp, hf::SE3::exp(xi)});
    stamp += 1.0 / 30.0;  // stamps that are not whole microseconds
  }
  t.push_back({stamp + 1e-7, hf::SE3()});  // closer than a microsecond to the previous one
  const std::string text = hf::format_tum_trajectory(t, "estimated by hashfusion\nsecond line");
  EXPECT_EQ(text.rfind("# estimated by hashfusion\n# second line\n", 0), 0u) << text.substr(0, 80);
  const hf::Trajectory back = hf::parse_tum_trajectory(text, "round-trip");
  ASSERT_EQ(back.size(), t.size());
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_EQ(back[i].timestamp_s, t[i].timestamp_s) << i;
    EXPECT_EQ(back[i].T_world_camera.translation(), t[i].T_world_camera.translation()) << i;
    EXPECT_NEAR((back[i].T_world_camera.matrix() - t[i].T_world_camera.matrix()).cwiseAbs().maxCoeff(), 0.0, 1e-15);
  }
  // TUM's own stamps keep their familiar six decimals.
  EXPECT_TRUE(contains(text, "\n1305031229.528748 ")) << text.substr(0, 200);
}

TEST(TrajectoryIo, WriteIsAtomicAndReadNamesMissingFiles) {
  hf::test::TempDir dir("traj");
  const std::string path = dir / "est.txt";
  const hf::Trajectory t = {{1.0, hf::SE3()}, {2.0, hf::SE3(Eigen::Quaterniond::Identity(), {1, 2, 3})}};
  hf::write_tum_trajectory(path, t);
  const hf::Trajectory back = hf::read_tum_trajectory(path);
  ASSERT_EQ(back.size(), 2u);
  EXPECT_EQ(back[1].T_world_camera.translation(), Eigen::Vector3d(1, 2, 3));
  size_t files = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir.path)) files += e.is_regular_file();
  EXPECT_EQ(files, 1u);
  const std::string missing = dir / "missing.txt";
  EXPECT_TRUE(contains(error_of([&] { hf::read_tum_trajectory(missing); }), missing));
  EXPECT_FALSE(error_of([&] { hf::write_tum_trajectory(dir / "no/such/dir.txt", t); }).empty());
}

// Issue 14.9: tx = 1e308 is finite but no physical pose; it made the ATE -nan. Coordinates beyond 1e6 m and stamps
// beyond 1e12 s are refused with file and line.
TEST(TrajectoryIo, CoordinatesAndStampsBeyondAPhysicalBoundAreRefused) {
  EXPECT_TRUE(contains(error_of([] { hf::parse_tum_trajectory("1 0 0 0 0 0 0 1\n2 1e308 0 0 0 0 0 1\n", "gt.txt"); }),
                       "gt.txt:2: expected coordinates within 1e6 m (a physical bound), got '1e308'"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_tum_trajectory("1 0 0 -1000001 0 0 0 1\n", "gt.txt"); }), "gt.txt:1:"));
  EXPECT_TRUE(contains(error_of([] { hf::parse_tum_trajectory("1e300 0 0 0 0 0 0 1\n", "gt.txt"); }),
                       "gt.txt:1: expected a time stamp within 1e12 s"));
  const hf::Trajectory edge = hf::parse_tum_trajectory("1 1e6 -1e6 999999.5 0 0 0 1\n", "gt.txt");
  ASSERT_EQ(edge.size(), 1u);
  EXPECT_EQ(edge[0].T_world_camera.translation().x(), 1e6);
}

// Issue 14.8: the offending token used to be echoed whole (a 10 MB line) with its escape sequences.
TEST(TrajectoryIo, OffendingTokenIsQuotedShortAndPrintable) {
  std::string text = "1 0 0 0 0 0 0 1\n2 \x1b[31m";  // built by append: gcc 12 misreads operator+ here
  text.append(1000, 'x').append(" 0 0 0 0 0 1\n");
  const std::string msg = error_of([&] { hf::parse_tum_trajectory(text, "gt.txt"); });
  EXPECT_TRUE(contains(msg, "gt.txt:2: expected a finite number, got '?[31mxxx")) << msg;
  EXPECT_LT(msg.size(), 120u) << msg;
  EXPECT_EQ(msg.find('\x1b'), std::string::npos);
  std::string long_line = "1 0 0 0 0 0 0 1\n";
  long_line.append(5000, ' ').append("2 0 0 0 0 0 0 1\n");
  EXPECT_TRUE(contains(error_of([&] { hf::parse_tum_trajectory(long_line, "gt.txt"); }),
                       "gt.txt:2: expected a line of at most 4096 bytes, got 5015"));
}

TEST(TrajectoryIo, ReadsOnlyRegularFiles) {
  hf::test::TempDir dir("traj_kinds");
  EXPECT_TRUE(contains(error_of([&] { hf::read_tum_trajectory(dir.str()); }), "a folder, not a regular file"));
  if (std::filesystem::exists("/dev/zero")) {
    std::filesystem::create_symlink("/dev/zero", dir / "zero.txt");
    EXPECT_TRUE(contains(error_of([&] { hf::read_tum_trajectory(dir / "zero.txt"); }), "character device"));
  }
}

// One typed pose ("view --camera-pose"): TUM's order without the stamp, the quaternion normalised; anything else is
// one message naming the option and the offending token.
TEST(TrajectoryIo, TypedPoseInTumOrder) {
  const hf::SE3 T = hf::parse_tum_pose(" 1.5 -2 0.25  0 0 0.70710678118654752 0.70710678118654752 ", "--camera-pose");
  EXPECT_NEAR((T.translation() - Eigen::Vector3d(1.5, -2, 0.25)).norm(), 0.0, 1e-15);
  // qz = qw = 1/sqrt(2): 90 degrees about z, so the camera's x axis points along world y.
  EXPECT_NEAR((T.rotation() * Eigen::Vector3d::UnitX() - Eigen::Vector3d::UnitY()).norm(), 0.0, 1e-12);
  const hf::SE3 scaled = hf::parse_tum_pose("0 0 0 0 0 0 2", "p");  // normalised, as trajectory lines are
  EXPECT_NEAR((scaled.rotation() - Eigen::Matrix3d::Identity()).norm(), 0.0, 1e-15);
  const std::pair<std::string, std::string> cases[] = {
      {"", "expected 7 numbers 'tx ty tz qx qy qz qw', got 0"},
      {"1 2 3", "got 3"},
      {"0 0 0 0 0 0 1 5", "got more"},
      {"0 0 abc 0 0 0 1", "got 'abc'"},
      {"0 0 0 0 0 0 nan", "got 'nan'"},
      {"0 0 1e7 0 0 0 1", "expected coordinates within 1e6 m"},
      {"0 0 0 0 0 0 0", "expected a non-zero quaternion"},
  };
  for (const auto& [text, expect] : cases) {
    const std::string pose = text;  // clang 14 cannot capture a structured binding
    const std::string msg = error_of([&] { hf::parse_tum_pose(pose, "view: --camera-pose"); });
    EXPECT_TRUE(contains(msg, "view: --camera-pose: ")) << text << " -> " << msg;
    EXPECT_TRUE(contains(msg, expect)) << text << " -> " << msg;
    EXPECT_EQ(msg.find('\n'), std::string::npos) << msg;
  }
}
