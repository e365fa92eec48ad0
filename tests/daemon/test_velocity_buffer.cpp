// The velocity the rectifier sees: interpolated in time, refused when stale or insane.
#include <gtest/gtest.h>

#include <cmath>

#include "daemon/velocity_buffer.hpp"

using namespace rsd::daemon;
using rsd::drivers::VelocitySample;

namespace {
VelocitySample sample(int64_t t_ms, double wz, double vx = 0) {
  VelocitySample s;
  s.t_ns = t_ms * 1000000;
  s.w[2] = wz;
  s.v[0] = vx;
  s.has_linear = true;
  return s;
}
}  // namespace

TEST(VelocityBuffer, InterpolatesBetweenSamples) {
  VelocityBuffer b;
  ASSERT_TRUE(b.push(sample(0, 1.0, 2.0)));
  ASSERT_TRUE(b.push(sample(10, 2.0, 4.0)));
  VelocityEstimate e;
  ASSERT_EQ(b.at(2500000, e), VelocityStatus::Ok);
  EXPECT_NEAR(e.sample.w[2], 1.25, 1e-12);
  EXPECT_NEAR(e.sample.v[0], 2.5, 1e-12);
  EXPECT_EQ(e.age_s, 0.0);
}

TEST(VelocityBuffer, HoldsTheNewestWithinMaxAgeThenGoesStale) {
  VelocityBuffer b({20, 100, 0.05});
  b.push(sample(0, 1.0));
  b.push(sample(10, 3.0));
  VelocityEstimate e;
  ASSERT_EQ(b.at(40 * 1000000, e), VelocityStatus::Ok);
  EXPECT_NEAR(e.sample.w[2], 3.0, 1e-12);
  EXPECT_NEAR(e.age_s, 0.030, 1e-12);
  EXPECT_EQ(b.at(70 * 1000000, e), VelocityStatus::Stale);
  EXPECT_EQ(b.at(-5 * 1000000, e), VelocityStatus::Stale);  // before anything held
  VelocityBuffer empty;
  EXPECT_EQ(empty.at(0, e), VelocityStatus::NoData);
}

TEST(VelocityBuffer, RejectsInsaneAndBackwardSamples) {
  VelocityBuffer b({20, 100, 0.1});
  EXPECT_TRUE(b.push(sample(0, 1.0)));
  EXPECT_FALSE(b.push(sample(5, 25.0)));           // beyond max angular rate
  EXPECT_FALSE(b.push(sample(6, 1.0, 500.0)));     // beyond max linear speed
  EXPECT_FALSE(b.push(sample(0, 1.0)));            // not after the previous sample
  VelocitySample nan = sample(7, 1.0);
  nan.w[0] = std::nan("");
  EXPECT_FALSE(b.push(nan));
  EXPECT_EQ(b.rejected(), 4u);
  EXPECT_EQ(b.count(), 1u);
}

TEST(VelocityBuffer, ManySamplesWrapTheRing) {
  VelocityBuffer b;
  for (int i = 0; i < 5000; ++i) b.push(sample(i, i * 0.001));
  VelocityEstimate e;
  ASSERT_EQ(b.at(4990500000LL, e), VelocityStatus::Ok);  // t = 4990.5 ms
  EXPECT_NEAR(e.sample.w[2], 4.9905, 1e-9);
}

// Issue 16, defect 1: one plausible far-future stamp made every later sample "not after the
// previous one": rectification stopped until a restart. Now a stray off the time line is held,
// then dropped (counted) when the line goes on.
TEST(VelocityBuffer, OneFarFutureSampleIsDroppedAndTheLineGoesOn) {
  VelocityBuffer b;
  for (int t = 0; t < 100; ++t) ASSERT_TRUE(b.push(sample(t, 1.0)));
  EXPECT_FALSE(b.push(sample(1000LL * 86400 * 365, 1.0)));  // a year ahead
  EXPECT_FALSE(b.push(sample(99, 1.0)));                    // a repeated stamp
  for (int t = 100; t < 200; ++t) ASSERT_TRUE(b.push(sample(t, 2.0))) << t;
  VelocityEstimate e;
  ASSERT_EQ(b.at(150 * 1000000, e), VelocityStatus::Ok);
  EXPECT_EQ(e.sample.w[2], 2.0);
  EXPECT_EQ(b.rejected(), 2u);
  EXPECT_EQ(b.time_line_changes(), 0u);
}

// The wild stamp came first (or the sensor's clock restarted): kNewTimeLine consistent samples
// replace the line, none of them lost, and readers no longer see the old one.
TEST(VelocityBuffer, AConsistentNewTimeLineReplacesAWildOne) {
  VelocityBuffer b;
  ASSERT_TRUE(b.push(sample(1000LL * 86400 * 365, 5.0)));  // the first sample: a year ahead
  for (int t = 0; t < VelocityBuffer::kNewTimeLine - 1; ++t) EXPECT_FALSE(b.push(sample(t, 1.0 + t)));
  EXPECT_TRUE(b.push(sample(VelocityBuffer::kNewTimeLine - 1, 1.0 + VelocityBuffer::kNewTimeLine - 1)));
  EXPECT_EQ(b.time_line_changes(), 1u);
  EXPECT_EQ(b.rejected(), 0u);  // the held samples all went in
  VelocityEstimate e;
  ASSERT_EQ(b.at(2500000, e), VelocityStatus::Ok);  // 2.5 ms: between the held samples 2 and 3
  EXPECT_NEAR(e.sample.w[2], 3.5, 1e-12);
  EXPECT_EQ(b.newest_ns(), (VelocityBuffer::kNewTimeLine - 1) * 1000000LL);
  for (int t = VelocityBuffer::kNewTimeLine; t < 50; ++t) EXPECT_TRUE(b.push(sample(t, 1.0)));
  ASSERT_EQ(b.at(40 * 1000000, e), VelocityStatus::Ok);
  EXPECT_EQ(b.at(1000LL * 86400 * 365 * 1000000, e), VelocityStatus::Stale);  // the wild line is gone
}

// Strays that do not form a line (alternating wild stamps) never replace the real one.
TEST(VelocityBuffer, ScatteredStraysNeverReplaceTheLine) {
  VelocityBuffer b;
  int64_t t = 0;
  for (int i = 0; i < 400; ++i) {
    ASSERT_TRUE(b.push(sample(t++, 1.0)));
    EXPECT_FALSE(b.push(sample((i % 2 ? 1 : -1) * 1000000LL * (i + 2), 9.0)));
  }
  EXPECT_EQ(b.time_line_changes(), 0u);
  EXPECT_EQ(b.rejected(), 400u);
  VelocityEstimate e;
  ASSERT_EQ(b.at(399 * 1000000, e), VelocityStatus::Ok);
  EXPECT_EQ(e.sample.w[2], 1.0);
}

// A horizon of n samples answers as a buffer that was given only those n (a replayed frame sees
// the samples before the next frame, however many the reader pushed since).
TEST(VelocityBuffer, AHorizonAnswersAsTheBufferOfItsSamplesAlone) {
  VelocityBuffer all, first;
  const uint64_t horizon = 30;
  for (int64_t i = 0; i < 100; ++i) {
    all.push(sample(i * 5, std::sin(0.1 * static_cast<double>(i))));
    if (static_cast<uint64_t>(i) < horizon) first.push(sample(i * 5, std::sin(0.1 * static_cast<double>(i))));
  }
  EXPECT_EQ(all.newest_ns(horizon), first.newest_ns());
  EXPECT_EQ(all.newest_ns(VelocityBuffer::kAll), all.newest_ns());
  for (int64_t t_us = -1000; t_us < 300000; t_us += 777) {
    VelocityEstimate a, b;
    const VelocityStatus sa = all.at(t_us * 1000, a, horizon), sb = first.at(t_us * 1000, b);
    ASSERT_EQ(sa, sb) << t_us;
    if (sa != VelocityStatus::Ok) continue;
    EXPECT_EQ(a.sample.w[2], b.sample.w[2]) << t_us;
    EXPECT_EQ(a.age_s, b.age_s) << t_us;
  }
  // Samples the ring has since overwritten are not answered from.
  VelocityBuffer lapped;
  for (int64_t i = 0; i < static_cast<int64_t>(VelocityBuffer::kCapacity); ++i) lapped.push(sample(i, 1.0));
  VelocityEstimate e;
  EXPECT_EQ(lapped.at(5 * 1000000, e, 10), VelocityStatus::Stale);
  EXPECT_EQ(lapped.newest_ns(10), INT64_MIN);
}
