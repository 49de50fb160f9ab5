// `hashfusion eval` (apps/cmd_eval.cpp): options, JSON output, the plot, and one-line errors for bad files.
#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "apps/commands.h"
#include "core/error.h"
#include "io/trajectory_io.h"

namespace hf {
namespace {

class CmdEval : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = std::filesystem::temp_directory_path() / ("hf_cmd_eval_test_" + std::to_string(::getpid()));
    std::filesystem::create_directories(dir_);
    Trajectory gt, est;
    for (int k = 0; k <= 90; ++k) {
      const double t = 10.0 + k / 30.0;
      gt.push_back({t, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.5 * (t - 10.0), 0.2 * (k % 3), 0))});
      est.push_back(
          {t + 0.003, SE3(Eigen::Quaterniond::Identity(), Eigen::Vector3d(0.6 * (t - 10.0), 0.2 * (k % 3), 0))});
    }
    write_tum_trajectory(path("gt.txt"), gt);
    write_tum_trajectory(path("est.txt"), est);
  }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string path(const std::string& name) const { return (dir_ / name).string(); }

  // Runs `hashfusion eval ARGS` as main() would, returning stdout; exceptions propagate.
  std::string run(std::vector<std::string> args) {
    CLI::App app{"test"};
    app.require_subcommand(1);
    apps::add_eval_command(app);
    args.insert(args.begin(), "eval");
    std::reverse(args.begin(), args.end());  // CLI11's vector overload takes the arguments in reverse order
    std::ostringstream captured;
    std::streambuf* old = std::cout.rdbuf(captured.rdbuf());
    try {
      app.parse(args);
    } catch (...) {
      std::cout.rdbuf(old);
      throw;
    }
    std::cout.rdbuf(old);
    return captured.str();
  }

  std::filesystem::path dir_;
};

TEST_F(CmdEval, JsonHasTheDocumentedFieldsAndValues) {
  const std::string out = run({"--gt", path("gt.txt"), "--est", path("est.txt"), "--json"});
  const nlohmann::json j = nlohmann::json::parse(out);
  for (const char* key :
       {"pairs", "ate_rmse_m", "ate_mean_m", "ate_median_m", "ate_std_m", "ate_min_m", "ate_max_m", "rpe_pairs",
        "rpe_trans_rmse_m_per_s", "rpe_trans_mean_m_per_s", "rpe_rot_rmse_deg_per_s", "rpe_rot_mean_deg_per_s"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j.at("pairs"), 91);
  EXPECT_EQ(j.at("rpe_pairs"), 60);
  // 0.6 vs 0.5 m/s along x, same y: the relative motion over 1 s is 0.1 m too long.
  EXPECT_NEAR(j.at("rpe_trans_mean_m_per_s").get<double>(), 0.1, 1e-9);
  EXPECT_NEAR(j.at("rpe_rot_rmse_deg_per_s").get<double>(), 0.0, 1e-9);
  EXPECT_GT(j.at("ate_rmse_m").get<double>(), 0.0);
}

TEST_F(CmdEval, TableAndPlot) {
  const std::string out = run({"--gt", path("gt.txt"), "--est", path("est.txt"), "--plot", path("ate.png")});
  EXPECT_NE(out.find("ATE"), std::string::npos) << out;
  EXPECT_NE(out.find("RPE trans"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(path("ate.png")));
}

TEST_F(CmdEval, MalformedFileIsAParseErrorNamingFileAndLine) {
  std::ofstream(path("bad.txt")) << "# header\n1.0 0 0 0 0 0 0 1\n2.0 0 0 zero 0 0 0 1\n";
  try {
    run({"--gt", path("gt.txt"), "--est", path("bad.txt")});
    FAIL() << "expected hf::ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find(path("bad.txt") + ":3:"), std::string::npos) << e.what();
  }
  EXPECT_THROW(run({"--gt", path("missing.txt"), "--est", path("est.txt")}), Error);
}

TEST_F(CmdEval, NoPairsIsAClearError) {
  try {
    run({"--gt", path("gt.txt"), "--est", path("est.txt"), "--offset", "100"});
    FAIL() << "expected hf::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("no pose pairs within 0.02 s"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace hf
