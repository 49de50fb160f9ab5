// The benchmark's tables on hand-made numbers: won-lost-tie and mean-error ratios (the form of Table 1 of the
// registration report), the Pareto front, and the CSV / JSON files read back exactly.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "bench/harness/harness.h"
#include "bench/harness/results.h"
#include "core/error.h"

namespace hf::bench {
namespace {

RunRow run(const std::string& method, const std::string& input, std::optional<double> ate, long frames = 10,
           long lost = 0) {
  RunRow r;
  r.method = method;
  r.input = input;
  r.source = "source of " + input;
  r.ate_rmse_m = ate;
  r.frames = frames;
  r.frames_lost = lost;
  return r;
}

RunRow failed(const std::string& method, const std::string& input) {
  RunRow r = run(method, input, std::nullopt);
  r.failed = true;
  r.error = "capacity exhausted";
  return r;
}

// A, B, C over five inputs:
//   i1: A 0.010, B 0.020, C 0.0104     (A~C within 5%: tie)
//   i2: A 0.030, B 0.015, C failed
//   i3: A lost 6 of 10 frames (ATE 0.001 ignored), B 0.05, C 0.04 (25% apart)
//   i4: no ground truth (no run has an ATE): left out
//   i5: A failed, B failed, C 0.02     (A-B: both lost, a tie)
std::vector<RunRow> example() {
  return {run("A", "i1", 0.010), run("B", "i1", 0.020), run("C", "i1", 0.0104),
          run("A", "i2", 0.030), run("B", "i2", 0.015), failed("C", "i2"),
          run("A", "i3", 0.001, 10, 6), run("B", "i3", 0.05), run("C", "i3", 0.04),
          run("A", "i4", std::nullopt), run("B", "i4", std::nullopt), run("C", "i4", std::nullopt),
          failed("A", "i5"), failed("B", "i5"), run("C", "i5", 0.02)};
}

TEST(BenchResults, ComparableRule) {
  EXPECT_TRUE(run("A", "x", 0.01).comparable());
  EXPECT_TRUE(run("A", "x", 0.01, 10, 5).comparable());   // exactly half lost: still compared
  EXPECT_FALSE(run("A", "x", 0.01, 10, 6).comparable());  // more than half lost
  EXPECT_FALSE(run("A", "x", std::nullopt).comparable());
  EXPECT_FALSE(failed("A", "x").comparable());
  EXPECT_FALSE(run("A", "x", NAN).comparable());
}

TEST(BenchResults, CompareRunsTieWithinFivePercent) {
  EXPECT_EQ(compare_runs(run("A", "x", 0.100), run("B", "x", 0.105)), Outcome::tie);   // 4.8% of the larger
  EXPECT_EQ(compare_runs(run("A", "x", 0.100), run("B", "x", 0.1053)), Outcome::win);  // 5.03%
  EXPECT_EQ(compare_runs(run("A", "x", 0.1053), run("B", "x", 0.100)), Outcome::loss);
  EXPECT_EQ(compare_runs(failed("A", "x"), failed("B", "x")), Outcome::tie);
  EXPECT_EQ(compare_runs(run("A", "x", 0.5), failed("B", "x")), Outcome::win);
  EXPECT_EQ(compare_runs(failed("A", "x"), run("B", "x", 0.5)), Outcome::loss);
}

TEST(BenchResults, WonLostTieAndRatios) {
  const WltTable t = won_lost_tie(example(), {"A", "B", "C"});
  ASSERT_EQ(t.methods.size(), 3u);
  EXPECT_EQ(t.inputs, 4);  // i4 has no ground truth
  auto expect = [&](size_t r, size_t c, int w, int l, int ti) {
    SCOPED_TRACE("row " + std::to_string(r) + " column " + std::to_string(c));
    EXPECT_EQ(t.wlt[r][c].wins, w);
    EXPECT_EQ(t.wlt[r][c].losses, l);
    EXPECT_EQ(t.wlt[r][c].ties, ti);
  };
  // Lower triangle: column against row.
  expect(1, 0, 1, 2, 1);  // A vs B: i1 win, i2 loss, i3 loss (lost), i5 tie (both failed)
  expect(2, 0, 1, 2, 1);  // A vs C: i1 tie, i2 win (C failed), i3 loss, i5 loss
  expect(2, 1, 1, 3, 0);  // B vs C: i1 loss, i2 win, i3 loss, i5 loss
  // The upper triangle holds the mirror image.
  expect(0, 1, 2, 1, 1);
  expect(1, 2, 3, 1, 0);
  // Ratios ME(row) / ME(column) over the inputs both tracked.
  ASSERT_TRUE(t.ratio[0][1] && t.ratio[0][2] && t.ratio[1][2]);
  EXPECT_NEAR(*t.ratio[0][1], (0.010 + 0.030) / (0.020 + 0.015), 1e-12);  // i1, i2
  EXPECT_NEAR(*t.ratio[0][2], 0.010 / 0.0104, 1e-12);                     // i1 only
  EXPECT_NEAR(*t.ratio[1][2], (0.020 + 0.05) / (0.0104 + 0.04), 1e-12);   // i1, i3
  EXPECT_NEAR(*t.ratio[1][0] * *t.ratio[0][1], 1.0, 1e-12);
  EXPECT_EQ(t.common_inputs[0][1], 2);
  EXPECT_EQ(t.common_inputs[0][2], 1);
}

// The same table by translational RPE: each run's RPE decides, and a run without an RPE is lost for it even when
// it has an ATE. Here every RPE is ten times the ATE except A's on i1, which is worse than B's: A vs B on i1
// becomes a loss, the ratios follow the RPEs.
TEST(BenchResults, WonLostTieByRpe) {
  std::vector<RunRow> runs = example();
  for (RunRow& r : runs) {
    if (r.ate_rmse_m) r.rpe_trans_m_per_s = 10.0 * *r.ate_rmse_m;
    if (r.method == "A" && r.input == "i1") r.rpe_trans_m_per_s = 0.5;
  }
  const WltTable ate = won_lost_tie(runs, {"A", "B", "C"});
  const WltTable rpe = won_lost_tie(runs, {"A", "B", "C"}, ErrorMetric::rpe_translation);
  EXPECT_EQ(ate.wlt[1][0].wins, 1);
  EXPECT_EQ(rpe.wlt[1][0].wins, 0);  // i1: A's RPE 0.5 against B's 0.2
  EXPECT_EQ(rpe.wlt[1][0].losses, 3);
  ASSERT_TRUE(rpe.ratio[0][1]);
  EXPECT_NEAR(*rpe.ratio[0][1], (0.5 + 0.30) / (0.20 + 0.15), 1e-12);
  EXPECT_NE(format_wlt_markdown(rpe).find("by translational RPE"), std::string::npos);
  runs[0].rpe_trans_m_per_s.reset();  // A on i1 without an RPE: lost by RPE, still tracked by ATE
  EXPECT_EQ(compare_runs(runs[0], runs[1], ErrorMetric::rpe_translation), Outcome::loss);
  EXPECT_EQ(compare_runs(runs[0], runs[1]), Outcome::win);
}

// The per-frame-pair RPE is a third metric of its own: only rpe_frame_trans_m decides, the 1 s RPE is ignored.
TEST(BenchResults, WonLostTieByPerFrameRpe) {
  std::vector<RunRow> runs = example();
  for (RunRow& r : runs) {
    if (r.ate_rmse_m) r.rpe_frame_trans_m = *r.ate_rmse_m / 10.0;
    if (r.method == "B" && r.input == "i1") r.rpe_frame_trans_m = 0.0001;  // B now beats A on i1
  }
  const WltTable by_frame = won_lost_tie(runs, {"A", "B", "C"}, ErrorMetric::rpe_frame_translation);
  const WltTable by_second = won_lost_tie(runs, {"A", "B", "C"}, ErrorMetric::rpe_translation);
  EXPECT_EQ(by_frame.wlt[1][0].wins, 0);  // A against B: i1 lost (0.001 vs 0.0001), i2 lost, i3 lost
  EXPECT_EQ(by_frame.wlt[1][0].losses, 3);
  ASSERT_TRUE(by_frame.ratio[0][1]);
  EXPECT_NEAR(*by_frame.ratio[0][1], (0.001 + 0.003) / (0.0001 + 0.0015), 1e-12);
  EXPECT_EQ(by_second.wlt[1][0].wins + by_second.wlt[1][0].losses, 0);  // no run has a 1 s RPE: all ties
  EXPECT_NE(format_wlt_markdown(by_frame).find("by translational RPE (1 frame)"), std::string::npos);
  EXPECT_EQ(metric_name(ErrorMetric::rpe_translation), "translational RPE (1 s)");
}

TEST(BenchResults, WltMarkdownHasTheReportsForm) {
  const std::string md = format_wlt_markdown(won_lost_tie(example(), {"A", "B", "C"}));
  EXPECT_NE(md.find("| **B** | 1-2-1 | | 1.389 |"), std::string::npos) << md;
  EXPECT_NE(md.find("| **C** | 1-2-1 | 1-3-0 | |"), std::string::npos) << md;
  EXPECT_NE(md.find("| **A** | | 1.143 | 0.962 |"), std::string::npos) << md;
  EXPECT_NE(md.find("within 5%"), std::string::npos);
}

TEST(BenchResults, MethodWithoutCommonInputsHasNoRatio) {
  const std::vector<RunRow> runs = {run("A", "i1", 0.01), failed("B", "i1")};
  const WltTable t = won_lost_tie(runs, {"A", "B", "D"});  // D never ran
  EXPECT_FALSE(t.ratio[0][1]);
  EXPECT_EQ(t.wlt[1][0].wins, 1);
  EXPECT_EQ(t.wlt[2][0].wins + t.wlt[2][0].losses + t.wlt[2][0].ties, 0);
}

TEST(BenchResults, ParetoFront) {
  const std::vector<ParetoPoint> pts = {{1, 5}, {2, 3}, {3, 4}, {4, 1}, {2, 3}, {5, 1}, {NAN, 0}, {0.5, INFINITY}};
  const std::vector<size_t> front = pareto_front(pts);
  EXPECT_EQ(front, (std::vector<size_t>{0, 1, 4, 3}));
  EXPECT_TRUE(pareto_front({}).empty());
  EXPECT_EQ(pareto_front({{3, 3}}), (std::vector<size_t>{0}));
}

TEST(BenchResults, SummarizeMethods) {
  const auto s = summarize_methods(example(), {"A", "B", "C"});
  ASSERT_EQ(s.size(), 3u);
  EXPECT_EQ(s[0].inputs_run, 5);
  EXPECT_EQ(s[0].inputs_comparable, 2);  // i1, i2
  EXPECT_EQ(s[0].runs_failed, 1);
  ASSERT_TRUE(s[0].mean_ate_m);
  EXPECT_NEAR(*s[0].mean_ate_m, 0.02, 1e-12);
  EXPECT_EQ(s[2].inputs_comparable, 3);
}

RunRow awkward() {
  RunRow r = run("combined", "fr1, \"desk\"", 0.1 + 0.2, 123, 4);
  r.source = "TUM RGB-D 'data/a,b'";
  r.rpe_trans_m_per_s = 1.0 / 3.0;
  r.fps = 31.25;
  r.ms = {0.1, 1.0 / 7.0, 12.5, 3.0, 2.0, 17.7};
  r.wall_s = 4.0e-3;
  r.frames_bad = 2;
  r.coverage = 119.0 / 123.0;
  r.lost_spells = 3;
  r.longest_lost_spell = 2;
  r.worst_frame_ms = 1.0 / 3.0 + 80.0;
  r.rpe_frame_trans_m = 1.0 / 9.0;
  r.rpe_frame_rot_deg = 0.25;
  return r;
}

void expect_same(const RunRow& a, const RunRow& b) {
  EXPECT_EQ(a.method, b.method);
  EXPECT_EQ(a.peer, b.peer);
  EXPECT_EQ(a.input, b.input);
  EXPECT_EQ(a.source, b.source);
  EXPECT_EQ(a.failed, b.failed);
  EXPECT_EQ(a.interrupted, b.interrupted);
  EXPECT_EQ(a.error, b.error);
  EXPECT_EQ(a.frames, b.frames);
  EXPECT_EQ(a.frames_bad, b.frames_bad);
  EXPECT_EQ(a.frames_lost, b.frames_lost);
  EXPECT_EQ(a.ate_rmse_m, b.ate_rmse_m);  // exact: numbers are written in shortest round-trip form
  EXPECT_EQ(a.rpe_trans_m_per_s, b.rpe_trans_m_per_s);
  EXPECT_EQ(a.rpe_rot_deg_per_s, b.rpe_rot_deg_per_s);
  EXPECT_EQ(a.fps, b.fps);
  EXPECT_EQ(a.ms.read, b.ms.read);
  EXPECT_EQ(a.ms.preprocess, b.ms.preprocess);
  EXPECT_EQ(a.ms.track, b.ms.track);
  EXPECT_EQ(a.ms.integrate, b.ms.integrate);
  EXPECT_EQ(a.ms.raycast, b.ms.raycast);
  EXPECT_EQ(a.ms.total, b.ms.total);
  EXPECT_EQ(a.wall_s, b.wall_s);
  EXPECT_EQ(a.coverage, b.coverage);
  EXPECT_EQ(a.lost_spells, b.lost_spells);
  EXPECT_EQ(a.longest_lost_spell, b.longest_lost_spell);
  EXPECT_EQ(a.worst_frame_ms, b.worst_frame_ms);
  EXPECT_EQ(a.rpe_frame_trans_m, b.rpe_frame_trans_m);
  EXPECT_EQ(a.rpe_frame_rot_deg, b.rpe_frame_rot_deg);
}

std::vector<RunRow> round_trip_rows() {
  RunRow f = failed("gicp", "synthetic:wall");
  f.peer = true;
  f.error = "PCL said \"no\", twice\nthen gave up";
  RunRow i = run("icp", "synthetic:wall", std::nullopt, 3);
  i.interrupted = true;
  return {awkward(), f, i};
}

TEST(BenchResults, CsvRoundTrip) {
  const std::vector<RunRow> rows = round_trip_rows();
  const std::string csv = results_to_csv(rows);
  EXPECT_EQ(csv.rfind("method,peer,input,source,status,error,frames,", 0), 0u);
  const std::vector<RunRow> back = results_from_csv(csv, "results.csv");
  ASSERT_EQ(back.size(), rows.size());
  for (size_t k = 0; k < rows.size(); ++k) expect_same(rows[k], back[k]);
}

TEST(BenchResults, CsvErrorsNameFileAndLine) {
  try {
    results_from_csv("a,b\n", "x.csv");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()).rfind("x.csv:1:", 0), 0u) << e.what();
  }
  std::string csv = results_to_csv({awkward(), awkward()});
  const size_t pos = csv.find(",123,");  // frames of the second row (line 3)
  const size_t second = csv.find(",123,", pos + 1);
  csv.replace(second, 5, ",12x,");
  try {
    results_from_csv(csv, "x.csv");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.line(), 3);
    EXPECT_NE(std::string(e.what()).find("frames"), std::string::npos) << e.what();
  }
  EXPECT_THROW(results_from_csv("", "x.csv"), ParseError);
  EXPECT_THROW(results_from_csv(csv.substr(0, csv.find('\n') + 1) + "\"open quote", "x.csv"), ParseError);
}

TEST(BenchResults, JsonRoundTrip) {
  BenchResults b;
  b.machine = {"0123456789abcdef0123456789abcdef01234567", "hashfusion bench --input x", "Some CPU @ 2GHz",
               "2024-01-01T00:00:00Z", 2};
  b.methods = {"combined", "icp", "gicp (peer)"};
  b.inputs = {"fr1, \"desk\"", "synthetic:wall"};
  b.notes = {"skipping /x: not a TUM or 7-Scenes dataset"};
  b.settings = "voxel 0.01 m";
  b.runs = round_trip_rows();
  const nlohmann::json j = nlohmann::json::parse(results_to_json(b).dump(2));
  EXPECT_TRUE(j.at("runs").at(1).at("ate_rmse_m").is_null());
  EXPECT_TRUE(j.at("won_lost_tie").contains("rule"));
  const BenchResults back = results_from_json(j, "results.json");
  EXPECT_EQ(back.machine.commit, b.machine.commit);
  EXPECT_EQ(back.machine.command_line, b.machine.command_line);
  EXPECT_EQ(back.machine.cpu_model, b.machine.cpu_model);
  EXPECT_EQ(back.machine.cores, 2u);
  EXPECT_EQ(back.machine.date_utc, b.machine.date_utc);
  EXPECT_EQ(back.methods, b.methods);
  EXPECT_EQ(back.inputs, b.inputs);
  EXPECT_EQ(back.notes, b.notes);
  EXPECT_EQ(back.settings, b.settings);
  ASSERT_EQ(back.runs.size(), b.runs.size());
  for (size_t k = 0; k < b.runs.size(); ++k) expect_same(b.runs[k], back.runs[k]);
  EXPECT_THROW(results_from_json(nlohmann::json::object(), "r.json"), ParseError);
}

// bench --merge: a later folder's row of the same method and input replaces the earlier one, new methods and inputs
// are appended (peers after hashfusion methods), and the notes name each folder's commit and command.
TEST(BenchResults, MergeReplacesRowsOfLaterFolders) {
  const std::filesystem::path root =
      std::filesystem::temp_directory_path() / ("hf_bench_merge_" + std::to_string(::getpid()));
  std::filesystem::remove_all(root);
  BenchResults a;
  a.machine.commit = "aaa";
  a.machine.command_line = "hashfusion bench --input first";
  a.methods = {"icp", "gicp (peer)"};
  a.inputs = {"i1", "i2"};
  a.runs = {run("icp", "i1", 0.01), run("icp", "i2", 0.02), run("gicp", "i1", 0.03), run("gicp", "i2", 0.04)};
  a.runs[2].peer = a.runs[3].peer = true;
  BenchResults b;
  b.machine.commit = "bbb";
  b.machine.command_line = "hashfusion bench --input second";
  b.methods = {"icp", "o3d-icp (peer)", "sdf"};
  b.inputs = {"i2", "i3"};
  b.runs = {run("icp", "i2", 0.005), run("o3d-icp", "i2", 0.06), run("sdf", "i3", 0.07)};
  b.runs[1].peer = true;
  std::filesystem::create_directories(root / "a");
  std::filesystem::create_directories(root / "b");
  write_results((root / "a").string(), a, {});
  write_results((root / "b").string(), b, {});
  const BenchReport r =
      merge_bench({(root / "a").string(), (root / "b").string()}, (root / "m").string(), "", "hashfusion bench --merge");
  const BenchResults& m = r.results;
  EXPECT_EQ(m.methods, (std::vector<std::string>{"icp", "sdf", "gicp (peer)", "o3d-icp (peer)"}));
  EXPECT_EQ(m.inputs, (std::vector<std::string>{"i1", "i2", "i3"}));
  ASSERT_EQ(m.runs.size(), 6u);
  EXPECT_EQ(m.runs[1].input, "i2");
  EXPECT_EQ(m.runs[1].ate_rmse_m, 0.005);  // b's icp on i2 replaced a's in place
  ASSERT_EQ(m.notes.size(), 2u);
  EXPECT_NE(m.notes[0].find("commit aaa"), std::string::npos);
  EXPECT_NE(m.notes[1].find("hashfusion bench --input second"), std::string::npos);
  EXPECT_TRUE(std::filesystem::exists(root / "m" / "results.md"));
  EXPECT_THROW(merge_bench({(root / "none").string()}, (root / "m2").string(), "", ""), Error);
  std::filesystem::remove_all(root);
}

TEST(BenchResults, MarkdownHasRowsPerMethodAndMachine) {
  BenchResults b;
  b.machine.commit = "abc";
  b.machine.command_line = "hashfusion bench --input synthetic:wall";
  b.methods = {"A", "B", "C"};
  b.inputs = {"i1", "i2", "i3", "i4", "i5"};
  b.runs = example();
  const std::string md = results_to_markdown(b, {"speed_vs_error.png"});
  EXPECT_NE(md.find("`abc`"), std::string::npos);
  EXPECT_NE(md.find("### i3"), std::string::npos);
  EXPECT_NE(md.find("| C | failed: capacity exhausted |"), std::string::npos) << md;
  EXPECT_NE(md.find("![speed_vs_error.png](speed_vs_error.png)"), std::string::npos);
  EXPECT_NE(md.find("Won-lost-tie"), std::string::npos);
}

TEST(BenchResults, MachineInfo) {
  const MachineInfo m = current_machine("/nonexistent/folder", "cmd");
  EXPECT_EQ(m.commit, "unknown");
  EXPECT_EQ(m.command_line, "cmd");
  EXPECT_GE(m.cores, 1u);
  EXPECT_EQ(m.date_utc.size(), 20u);  // YYYY-MM-DDTHH:MM:SSZ
}

}  // namespace
}  // namespace hf::bench
