// The source watch (states, stall detector, frame-rate warning) on hand-made timelines, and the
// latency histogram against the sorted samples.
#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "daemon/latency_stats.hpp"
#include "daemon/source_watch.hpp"

using namespace rsd::daemon;

TEST(SourceWatch, StartingUntilTheFirstFrameHoweverLong) {
  SourceWatch w({}, "cam", 30, true);
  for (double t = 1; t < 60; t += 1) {
    const SourceWatch::Verdict v = w.update(t, 0, 0, 0);
    EXPECT_STREQ(v.state, "starting");
    EXPECT_TRUE(v.warning.empty());
  }
}

TEST(SourceWatch, StallAfterFivePeriodsAtLeastOneSecond) {
  EXPECT_DOUBLE_EQ(SourceWatch({}, "cam", 30, true).stall_after_s(), 1.0);
  EXPECT_DOUBLE_EQ(SourceWatch({}, "cam", 2, true).stall_after_s(), 2.5);
  EXPECT_DOUBLE_EQ(SourceWatch({}, "cam", 0, false).stall_after_s(), 1.0);
  HealthConfig c;
  c.stall_after_s = 0.3;
  EXPECT_DOUBLE_EQ(SourceWatch(c, "cam", 2, true).stall_after_s(), 0.3);
}

// Frames until 10 s, silence until 14 s, frames again: one warning when it stalls, one line
// when it streams again, states in between.
TEST(SourceWatch, StallIsSaidOnceAndItsEndToo) {
  SourceWatch w({}, "lcm:tcpq://127.0.0.1", 30, false);
  uint64_t frames = 0;
  std::vector<std::string> states, warnings, infos;
  for (int t = 1; t <= 18; ++t) {
    const bool delivering = t <= 10 || t >= 15;
    if (delivering) frames += 30;
    const double last = delivering ? t - 0.01 : 10.5;  // the last frame came half a second after t = 10
    const SourceWatch::Verdict v = w.update(t, frames, last, delivering ? 30 : 0);
    states.push_back(v.state);
    if (!v.warning.empty()) warnings.push_back(v.warning);
    if (!v.info.empty()) infos.push_back(v.info);
  }
  EXPECT_EQ(states[9], "streaming");  // t = 10
  EXPECT_EQ(states[10], "streaming");  // t = 11: 0.5 s silent
  EXPECT_EQ(states[11], "stalled");   // t = 12: 1.5 s silent, more than five periods and 1 s
  EXPECT_EQ(states[13], "stalled");   // t = 14
  EXPECT_EQ(states[14], "streaming");  // t = 15
  ASSERT_EQ(warnings.size(), 1u);
  EXPECT_NE(warnings[0].find("lcm:tcpq://127.0.0.1: stalled: no frame for 1.5 s (stall_after_s 1.0)"), std::string::npos) << warnings[0];
  ASSERT_EQ(infos.size(), 1u);
  EXPECT_NE(infos[0].find("streaming again"), std::string::npos);
}

// A camera at 60% of its configured rate: warned once after low_fps_after_s, told when back.
TEST(SourceWatch, LowFrameRateWarnedOnceAfterItsDelayAndRecovery) {
  HealthConfig c;
  c.low_fps_after_s = 3;
  SourceWatch w(c, "sim", 15, true);
  uint64_t frames = 0;
  int warned_at = -1, back_at = -1, warnings = 0;
  for (int t = 1; t <= 12; ++t) {
    const double fps = t <= 8 ? 9.0 : 15.0;
    frames += static_cast<uint64_t>(fps);
    const SourceWatch::Verdict v = w.update(t, frames, t - 0.05, fps);
    if (!v.warning.empty()) {
      warned_at = t, ++warnings;
      EXPECT_NE(v.warning.find("delivering 9.0 fps, below the configured 15.0 fps for 3 s"), std::string::npos) << v.warning;
    }
    if (!v.info.empty()) back_at = t;
  }
  EXPECT_EQ(warnings, 1);
  EXPECT_EQ(warned_at, 4);  // low from t = 1: three seconds later
  EXPECT_EQ(back_at, 9);
}

TEST(SourceWatch, NoRateWarningForUnpacedSourcesOrWithinTolerance) {
  SourceWatch replay({}, "replay", 30, false);
  SourceWatch camera({}, "cam", 30, true);
  uint64_t frames = 0;
  for (int t = 1; t <= 10; ++t) {
    frames += 28;
    EXPECT_TRUE(replay.update(t, frames, t - 0.01, 5).warning.empty());
    EXPECT_TRUE(camera.update(t, frames, t - 0.01, 28).warning.empty());  // 93% of 30
  }
}

// Quantiles against the sorted samples (within a bin), nothing clipped beyond the range.
TEST(LatencyStats, QuantilesMatchSortedSamplesAndOverRangeIsCountedNotClipped) {
  LatencyStats s;
  std::mt19937 rng(7);
  std::lognormal_distribution<double> d(0.5, 0.6);
  std::vector<double> v;
  for (int i = 0; i < 5000; ++i) v.push_back(d(rng)), s.add(v.back());
  std::sort(v.begin(), v.end());
  for (double q : {0.5, 0.9, 0.99}) {
    const double truth = v[static_cast<size_t>(q * (v.size() - 1))];
    EXPECT_NEAR(s.quantile(q), truth, LatencyStats::kBinMs) << q;
  }
  EXPECT_EQ(s.over_range(), 0u);
  // 2% of the frames beyond 100 ms: p99 is no longer in range and reports the largest seen.
  for (int i = 0; i < 102; ++i) s.add(120 + i);
  EXPECT_EQ(s.over_range(), 102u);
  EXPECT_DOUBLE_EQ(s.max_ms(), 221);
  EXPECT_DOUBLE_EQ(s.quantile(0.99), 221);
  EXPECT_LT(s.quantile(0.5), 5);
  s.reset();
  EXPECT_EQ(s.over_range(), 0u);
  EXPECT_EQ(s.quantile(0.99), 0);
}
