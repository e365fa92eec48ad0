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
