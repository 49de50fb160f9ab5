#include "core/timing.h"

#include <gtest/gtest.h>

namespace hf {
namespace {

TEST(StageTimes, AccumulatesSumsCountsAndMeans) {
  StageTimes t;
  EXPECT_EQ(t.mean_ms("track"), 0.0);
  EXPECT_EQ(t.count("track"), 0);
  EXPECT_EQ(t.total_ms("track"), 0.0);
  t.add("track", 2.0);
  t.add("track", 4.0);
  t.add("integrate", 1.5);
  EXPECT_EQ(t.count("track"), 2);
  EXPECT_DOUBLE_EQ(t.total_ms("track"), 6.0);
  EXPECT_DOUBLE_EQ(t.mean_ms("track"), 3.0);
  EXPECT_DOUBLE_EQ(t.mean_ms("integrate"), 1.5);
  EXPECT_EQ(t.stages().size(), 2u);
}

TEST(ScopedTimer, AddsOneNonNegativeSampleOnScopeExit) {
  StageTimes t;
  {
    ScopedTimer timer(t, "raycast");
    EXPECT_GE(timer.elapsed_ms(), 0.0);
    EXPECT_EQ(t.count("raycast"), 0);
  }
  EXPECT_EQ(t.count("raycast"), 1);
  EXPECT_GE(t.total_ms("raycast"), 0.0);
  { ScopedTimer timer(t, "raycast"); }
  EXPECT_EQ(t.count("raycast"), 2);
}

}  // namespace
}  // namespace hf
