// `hashfusion bench --shard K/N` (issue 37): the run list, the K/N parser and the slices a job array runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "bench/harness/harness.h"
#include "core/error.h"

namespace hf::bench {
namespace {

TEST(BenchShard, ParsesKOverN) {
  EXPECT_EQ(parse_shard("0/1"), std::make_pair(0, 1));
  EXPECT_EQ(parse_shard("5/6"), std::make_pair(5, 6));
  EXPECT_EQ(parse_shard("17/1000"), std::make_pair(17, 1000));
}

TEST(BenchShard, RefusesWhatIsNotASlice) {
  for (const std::string bad : {"", "1", "/2", "1/", "6/6", "-1/3", "1/0", "a/b", "1/2x", " 1/2", "1/2/3",
                                "99999999999/2", "0x1/2"}) {
    try {
      parse_shard(bad);
      ADD_FAILURE() << "accepted '" << bad << "'";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find("--shard '" + bad + "'"), std::string::npos) << e.what();
    }
  }
}

// Every run in exactly one slice, slices contiguous and in order, sizes within one of each other: the merge of
// slices 0..N-1 sees the runs in the single run's order.
TEST(BenchShard, SlicesCoverTheRunsOnceInOrder) {
  for (size_t runs = 1; runs <= 40; ++runs) {
    for (int n = 1; n <= int(runs); ++n) {
      size_t next = 0, smallest = runs, largest = 0;
      for (int k = 0; k < n; ++k) {
        const auto [first, last] = shard_range(runs, k, n);
        ASSERT_EQ(first, next) << runs << " runs, slice " << k << "/" << n;
        ASSERT_GT(last, first) << "an empty slice: " << runs << " runs, slice " << k << "/" << n;
        smallest = std::min(smallest, last - first), largest = std::max(largest, last - first);
        next = last;
      }
      EXPECT_EQ(next, runs);
      EXPECT_LE(largest - smallest, 1u);
    }
  }
}

TEST(BenchShard, PlansTheRunsInRunOrder) {
  BenchOptions o;
  o.inputs = {"synthetic:wall", "synthetic:room"};
  o.registrations = {"icp", "combined"};
  o.loop_closure_modes = {"on", "off"};
  o.peers = {"gicp"};
  const std::vector<PlannedRun> runs = plan_runs(o);
  const std::vector<std::string> methods = {"icp", "icp -loops", "combined", "combined -loops", "gicp (peer)"};
  ASSERT_EQ(runs.size(), 2 * methods.size());
  for (size_t k = 0; k < runs.size(); ++k) {
    EXPECT_EQ(runs[k].input, k < methods.size() ? "synthetic:wall" : "synthetic:room");
    EXPECT_EQ(runs[k].method, methods[k % methods.size()]);
  }
}

TEST(BenchShard, MoreSlicesThanRunsIsRefusedBeforeAnyRun) {
  BenchOptions o;
  o.inputs = {"synthetic:wall"};
  o.registrations = {"icp"};
  o.out = testing::TempDir() + "hf_bench_shard_refused";
  o.shard_index = 1, o.shard_count = 2;
  try {
    run_bench(o);
    ADD_FAILURE() << "2 slices of 1 run accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("only 1 run to share"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(std::filesystem::exists(o.out)) << "the output folder was created for a refused shard";
}

}  // namespace
}  // namespace hf::bench
