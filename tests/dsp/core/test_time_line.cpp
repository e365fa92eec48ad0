// The one time-line rule for stamps from outside (dsp/core/time_line.hpp), against its cases
// worked by hand, and against a brute-force restatement over random streams with wild stamps.
#include <gtest/gtest.h>

#include <random>
#include <vector>

#include "dsp/core/time_line.hpp"

using rsd::dsp::TimeLine;
using V = TimeLine::Verdict;

TEST(TimeLine, OneWildStampIsHeldAndTheLineGoesOn) {
  TimeLine l(10, 3);
  EXPECT_EQ(l.offer(100), V::Continues);
  EXPECT_EQ(l.offer(105), V::Continues);
  for (const int64_t wild : {INT64_MAX, INT64_MIN + 1, int64_t{1'000'000'000'000'000}, int64_t{105}, int64_t{50}, int64_t{116}}) {
    EXPECT_EQ(l.offer(wild), V::Held) << wild;
    EXPECT_EQ(l.offer(l.newest() + 5), V::Continues) << wild;  // the stream goes on
    EXPECT_EQ(l.held(), 0);
  }
}

TEST(TimeLine, AConsistentNewLineReplacesTheOldAfterConfirmStamps) {
  TimeLine l(10, 3);
  l.offer(1000);
  EXPECT_EQ(l.offer(5), V::Held);  // the clock restarted
  EXPECT_EQ(l.offer(10), V::Held);
  EXPECT_EQ(l.held(), 2);
  EXPECT_EQ(l.offer(15), V::Replaces);
  EXPECT_EQ(l.newest(), 15);
  EXPECT_EQ(l.offer(20), V::Continues);
  // The first stamp was the wild one: the real line takes over just the same.
  TimeLine w(10, 3);
  w.offer(INT64_MAX);
  EXPECT_EQ(w.offer(1), V::Held);
  EXPECT_EQ(w.offer(2), V::Held);
  EXPECT_EQ(w.offer(3), V::Replaces);
}

TEST(TimeLine, EqualStampsContinueOnlyWhenAllowed) {
  TimeLine strict(10, 3), events(10, 3, true);
  strict.offer(5), events.offer(5);
  EXPECT_EQ(strict.offer(5), V::Held);
  EXPECT_EQ(events.offer(5), V::Continues);  // two log events of one microsecond
  EXPECT_EQ(events.offer(4), V::Held);
}

TEST(TimeLine, ScatteredStraysNeverFormALine) {
  TimeLine l(10, 3);
  l.offer(0);
  int64_t t = 0;
  for (int i = 0; i < 100; ++i) {
    // Two strays far apart (not a line of their own), then the line goes on.
    EXPECT_EQ(l.offer(t + 1'000'000), V::Held);
    EXPECT_EQ(l.offer(t + 5'000'000), V::Held);
    EXPECT_EQ(l.offer(t += 7), V::Continues);
  }
}

// The rule restated the long way (128-bit differences), over random streams
// of good stamps, wild ones and clock restarts.
TEST(TimeLine, AgreesWithTheRuleRestatedOverRandomStreams) {
  std::mt19937_64 rng(11);
  for (int stream = 0; stream < 200; ++stream) {
    const int64_t gap = 1 + static_cast<int64_t>(rng() % 1000);
    const int confirm = 1 + static_cast<int>(rng() % 8);
    TimeLine l(gap, confirm);
    bool any = false;
    __int128 newest = 0;
    std::vector<__int128> run;
    int64_t clock = static_cast<int64_t>(rng() % 1'000'000) - 500'000;
    for (int i = 0; i < 300; ++i) {
      int64_t t;
      const unsigned kind = static_cast<unsigned>(rng() % 20);
      if (kind == 0) t = static_cast<int64_t>(rng());                          // wild
      else if (kind == 1) t = clock = static_cast<int64_t>(rng() % 1'000'000);  // restart
      else t = clock += 1 + static_cast<int64_t>(rng() % static_cast<uint64_t>(gap));
      const auto fits = [&](__int128 a, __int128 b) { return a > b && a - b <= static_cast<__int128>(gap); };
      V want;
      if (!any || fits(static_cast<__int128>(t), newest)) {
        want = V::Continues, any = true, newest = static_cast<__int128>(t), run.clear();
      } else {
        if (run.empty() || !fits(static_cast<__int128>(t), run.back())) run.clear();
        run.push_back(static_cast<__int128>(t));
        want = static_cast<int>(run.size()) < confirm ? V::Held : V::Replaces;
        if (want == V::Replaces) newest = static_cast<__int128>(t), run.clear();
      }
      ASSERT_EQ(l.offer(t), want) << "stream " << stream << " stamp " << i << " t " << t;
      ASSERT_EQ(l.held(), static_cast<int>(run.size()));
    }
  }
}
