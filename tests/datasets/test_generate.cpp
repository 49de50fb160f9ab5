// `hashfusion generate`: the real subcommand, parsed by CLI11 in process, writes a TUM folder that the dataset
// reader opens, byte-identical for a seed; bad arguments give one clear error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "apps/commands.h"
#include "core/camera.h"
#include "core/error.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/tum_writer.h"
#include "io/dataset.h"
#include "io/trajectory_io.h"

namespace hf::datasets {
namespace {

namespace fs = std::filesystem;

class Generate : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("hf_test_generate_" + std::to_string(::getpid()) + "_" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    fs::create_directories(root_);
    // A 160x120 camera keeps the renders fast; the writer and reader do not care about the size.
    small_camera_ = PinholeCamera::preset("ros").scaled(2);
    camera_file_ = (root_ / "small_camera.json").string();
    small_camera_.save(camera_file_);
  }
  void TearDown() override { fs::remove_all(root_); }

  // Runs `hashfusion generate ARGS...` through the real CLI definition.
  static void run(std::vector<std::string> args) {
    CLI::App app{"test"};
    apps::add_generate_command(app);
    args.insert(args.begin(), "generate");
    std::vector<const char*> argv{"hashfusion"};
    for (const auto& a : args) argv.push_back(a.c_str());
    app.parse(int(argv.size()), argv.data());
  }

  static std::string read_bytes(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
  }

  fs::path root_;
  PinholeCamera small_camera_;
  std::string camera_file_;
};

TEST_F(Generate, WritesAReadableTumFolder) {
  const fs::path out = root_ / "seq";
  run({"--preset", "room", "--frames", "4", "--seed", "7", "--out", out.string(), "--camera", camera_file_});
  for (const char* f : {"rgb.txt", "depth.txt", "groundtruth.txt", "camera.json"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  EXPECT_FALSE(fs::exists(out.string() + ".tmp"));
  EXPECT_EQ(std::distance(fs::directory_iterator(out / "rgb"), fs::directory_iterator{}), 4);
  EXPECT_EQ(std::distance(fs::directory_iterator(out / "depth"), fs::directory_iterator{}), 4);

  const Trajectory gt = read_tum_trajectory((out / "groundtruth.txt").string());
  ASSERT_EQ(gt.size(), 4u);
  SyntheticOptions o;
  o.preset = "room";
  o.frames = 4;
  o.seed = 7;
  o.camera = small_camera_;
  const SyntheticSequence seq(o);
  EXPECT_EQ(PinholeCamera::load((out / "camera.json").string()), seq.camera());

  // The TUM reader associates rgb.txt and depth.txt and attaches the ground truth.
  DatasetOptions dopt;
  dopt.prefetch_frames = 0;
  auto source = open_dataset(out.string(), dopt);
  ASSERT_EQ(source->size(), 4u);
  EXPECT_EQ(source->camera(), seq.camera());
  for (int i = 0; i < 4; ++i) {
    FrameRead r = source->next();
    ASSERT_EQ(r.status, FrameStatus::ok) << r.message;
    const SyntheticFrame f = seq.frame(i);
    EXPECT_NEAR(r.frame.timestamp_s, f.timestamp_s, 1e-9);
    EXPECT_NEAR(gt[i].timestamp_s, f.timestamp_s, 1e-9);
    EXPECT_TRUE(gt[i].T_world_camera.matrix().isApprox(f.T_world_camera.matrix(), 1e-12));
    ASSERT_TRUE(r.frame.T_world_camera_gt.has_value());
    EXPECT_TRUE(r.frame.T_world_camera_gt->matrix().isApprox(f.T_world_camera.matrix(), 1e-9));
    EXPECT_EQ(r.frame.color.pixels(), f.color.pixels());
    ASSERT_EQ(r.frame.depth.width(), small_camera_.width);
    ASSERT_EQ(r.frame.depth.size(), f.depth.size());
    for (size_t k = 0; k < f.depth.size(); ++k) {
      const float a = r.frame.depth.data()[k], b = f.depth.data()[k];
      ASSERT_EQ(a == 0.0f, b == 0.0f) << k;
      ASSERT_NEAR(a, b, 0.5 / 5000.0 + 1e-6) << k;  // 16-bit PNG at 1/5000 m
    }
  }
  EXPECT_EQ(source->next().status, FrameStatus::end);
}

TEST_F(Generate, SameSeedSameBytesDifferentSeedDifferentNoise) {
  const std::vector<std::string> base{"--preset", "wall", "--frames", "2", "--camera", camera_file_};
  auto args = [&](const std::string& seed, const fs::path& out) {
    std::vector<std::string> a = base;
    for (const auto& s : {std::string("--seed"), seed, std::string("--out"), out.string()}) a.push_back(s);
    return a;
  };
  run(args("5", root_ / "a"));
  run(args("5", root_ / "b"));
  run(args("6", root_ / "c"));
  for (const auto& entry : fs::recursive_directory_iterator(root_ / "a")) {
    if (!entry.is_regular_file()) continue;
    const fs::path rel = fs::relative(entry.path(), root_ / "a");
    EXPECT_EQ(read_bytes(root_ / "a" / rel), read_bytes(root_ / "b" / rel)) << rel;
  }
  const std::string stamp = tum_stamp(1.0 / 30.0);
  EXPECT_NE(read_bytes(root_ / "a" / "depth" / (stamp + ".png")), read_bytes(root_ / "c" / "depth" / (stamp + ".png")));
  EXPECT_NE(read_bytes(root_ / "a" / "rgb" / (stamp + ".png")), read_bytes(root_ / "c" / "rgb" / (stamp + ".png")));
  EXPECT_EQ(read_bytes(root_ / "a" / "groundtruth.txt"), read_bytes(root_ / "c" / "groundtruth.txt"));
}

TEST_F(Generate, NoNoiseWritesExactDepthUpToPngQuantisation) {
  const fs::path out = root_ / "exact";
  run({"--preset", "sphere", "--frames", "1", "--no-noise", "--out", out.string(), "--camera", camera_file_});
  SyntheticOptions o;
  o.preset = "sphere";
  o.frames = 1;
  o.camera = small_camera_;
  o.noise_enabled = false;
  const SyntheticFrame f = SyntheticSequence(o).frame(0);
  const DepthImage d = load_depth((out / "depth" / (tum_stamp(0.0) + ".png")).string());
  for (size_t k = 0; k < d.size(); ++k) ASSERT_NEAR(d.data()[k], f.depth_clean.data()[k], 0.5 / 5000.0 + 1e-6);
}

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  } catch (const CLI::ParseError& e) {  // a range check of the option (apps/cli_common.h)
    return e.what();
  }
  return "";
}

TEST_F(Generate, BadArgumentsGiveAClearError) {
  const std::string out = (root_ / "x").string();
  std::string m = error_of([&] { run({"--preset", "kitchen", "--frames", "2", "--out", out}); });
  EXPECT_NE(m.find("unknown synthetic preset 'kitchen'"), std::string::npos) << m;
  EXPECT_NE(m.find("corridor"), std::string::npos) << m;
  m = error_of([&] { run({"--frames", "0", "--out", out}); });
  EXPECT_NE(m.find("frames"), std::string::npos) << m;
  m = error_of([&] { run({"--frames", "-4", "--out", out}); });
  EXPECT_NE(m.find("--frames: expected 1..100000 frames, got -4"), std::string::npos) << m;
  m = error_of([&] { run({"--frames", "1", "--seed", "-1", "--out", out}); });  // not 2^64 - 1
  EXPECT_NE(m.find("--seed: expected 0..1.84467e+19, got -1"), std::string::npos) << m;
  EXPECT_FALSE(fs::exists(out));

  // An output below a regular file cannot be created (works as root too, unlike permission bits).
  std::ofstream(root_ / "file.txt") << "x";
  const std::string bad = (root_ / "file.txt" / "seq").string();
  m = error_of([&] { run({"--frames", "1", "--out", bad}); });
  EXPECT_NE(m.find(bad), std::string::npos) << m;
  EXPECT_NE(m.find("cannot create"), std::string::npos) << m;

  // An existing output is not replaced without --force, and is with it.
  const std::string ex = (root_ / "exists").string();
  run({"--frames", "2", "--out", ex, "--camera", camera_file_});
  m = error_of([&] { run({"--frames", "1", "--out", ex}); });
  EXPECT_NE(m.find("already exists"), std::string::npos) << m;
  run({"--frames", "1", "--out", ex, "--force", "--camera", camera_file_});
  EXPECT_EQ(PinholeCamera::load(ex + "/camera.json"), small_camera_);
  EXPECT_EQ(std::distance(fs::directory_iterator(root_ / "exists" / "rgb"), fs::directory_iterator{}), 1);

  m = error_of([&] { run({"--frames", "1", "--out", out, "--camera", "fr9"}); });
  EXPECT_NE(m.find("'fr9'"), std::string::npos) << m;

  // Without --out: out/generate of the working folder, as every subcommand's outputs go to out/SUBCOMMAND.
  const fs::path cwd = fs::current_path();
  fs::current_path(root_);
  run({"--frames", "1", "--camera", camera_file_});
  fs::current_path(cwd);
  EXPECT_EQ(PinholeCamera::load((root_ / "out" / "generate" / "camera.json").string()), small_camera_);
}

// Issue 14.2: "generate --out . --force" deleted the folder's contents and then failed; an unrelated
// "results.tmp" beside --out results was silently removed. Nothing but a previous output is ever replaced, and the
// build happens in a private folder of generate's own making.
TEST_F(Generate, ReplacesOnlyWhatAPreviousGenerateWrote) {
  fs::create_directories(root_ / "mine");
  std::ofstream(root_ / "mine" / "precious.txt") << "precious";
  const std::string mine = (root_ / "mine").string();
  std::string m = error_of([&] { run({"--frames", "1", "--out", mine, "--force", "--camera", camera_file_}); });
  EXPECT_NE(m.find("does not look like an output of hashfusion generate (it holds 'precious.txt')"), std::string::npos)
      << m;
  // A previous output with one stranger in it is not ours either.
  const std::string out = (root_ / "results").string();
  run({"--frames", "1", "--out", out, "--camera", camera_file_});
  std::ofstream(root_ / "results" / "rgb" / "notes.txt") << "mine";
  m = error_of([&] { run({"--frames", "1", "--out", out, "--force", "--camera", camera_file_}); });
  EXPECT_NE(m.find("'rgb/notes.txt'"), std::string::npos) << m;
  fs::remove(root_ / "results" / "rgb" / "notes.txt");
  // results.tmp, what the old writer used and removed, is someone else's now.
  fs::create_directories(root_ / "results.tmp");
  std::ofstream(root_ / "results.tmp" / "notes.txt") << "mine";
  run({"--frames", "2", "--out", out, "--force", "--camera", camera_file_});
  EXPECT_TRUE(fs::exists(root_ / "results.tmp" / "notes.txt"));
  EXPECT_TRUE(fs::exists(root_ / "mine" / "precious.txt"));
  // A link to a folder is not replaced (the folder it names would be).
  fs::create_directory_symlink(root_ / "results", root_ / "link");
  EXPECT_NE(error_of([&] { run({"--frames", "1", "--out", (root_ / "link").string(), "--force"}); }).find("not a folder"),
            std::string::npos);
  // Nothing is left behind: the listing is exactly what the test made.
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(root_)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  EXPECT_EQ(names, (std::vector<std::string>{"link", "mine", "results", "results.tmp", "small_camera.json"}));
}

TEST_F(Generate, RefusesTheWorkingFolderItsParentsTheRootAndHome) {
  const fs::path cwd = fs::current_path();
  fs::create_directories(root_ / "work" / "sub");
  fs::current_path(root_ / "work" / "sub");
  std::ofstream("precious.txt") << "precious";
  for (const std::string& out : {std::string("."), std::string(".."), std::string("./"), std::string("/")}) {
    const std::string m = error_of([&] { run({"--frames", "1", "--out", out, "--force"}); });
    EXPECT_NE(m.find("refusing to replace"), std::string::npos) << out << ": " << m;
  }
  fs::current_path(cwd);
  EXPECT_TRUE(fs::exists(root_ / "work" / "sub" / "precious.txt"));
  if (const char* home = std::getenv("HOME"); home && fs::is_directory(home)) {
    const std::string m = error_of([&] { run({"--frames", "1", "--out", home, "--force"}); });
    EXPECT_NE(m.find("refusing to replace the home folder"), std::string::npos) << m;
  }
}

}  // namespace
}  // namespace hf::datasets
