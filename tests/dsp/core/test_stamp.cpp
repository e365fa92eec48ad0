// rsd's one type for times from outside (dsp/core/stamp.hpp): the window's edges worked by hand,
// and every combination checked against 128-bit arithmetic (a different code path that cannot
// overflow) over random and extreme values.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "dsp/core/stamp.hpp"

using rsd::dsp::Stamp;

namespace {
constexpr int64_t kLimit = int64_t{1} << 61;  // 2.3e18 ns, written out independently of the header
}

TEST(Stamp, TheWindowIsPlusMinusTwoToTheSixtyOneNanoseconds) {
  EXPECT_TRUE(Stamp::from_ns(kLimit));
  EXPECT_TRUE(Stamp::from_ns(-kLimit));
  EXPECT_FALSE(Stamp::from_ns(kLimit + 1));
  EXPECT_FALSE(Stamp::from_ns(-kLimit - 1));
  EXPECT_FALSE(Stamp::from_ns(INT64_MAX));
  EXPECT_FALSE(Stamp::from_ns(INT64_MIN));
  // Microseconds: the last whole one inside, and no multiplication that overflows beyond.
  EXPECT_EQ(Stamp::from_us(kLimit / 1000)->ns(), kLimit / 1000 * 1000);
  EXPECT_FALSE(Stamp::from_us(kLimit / 1000 + 1));
  EXPECT_FALSE(Stamp::from_us(INT64_MAX));
  EXPECT_FALSE(Stamp::from_us(INT64_MIN));
  // Seconds: 73 years either way; NaN and infinities never.
  EXPECT_EQ(Stamp::from_s(1.5)->ns(), 1'500'000'000);
  EXPECT_EQ(Stamp::from_s(-2e9)->ns(), -2'000'000'000'000'000'000);
  EXPECT_FALSE(Stamp::from_s(2.4e9));
  EXPECT_FALSE(Stamp::from_s(1e300));
  EXPECT_FALSE(Stamp::from_s(std::nan("")));
  EXPECT_FALSE(Stamp::from_s(-std::numeric_limits<double>::infinity()));
}

TEST(Stamp, MicrosecondsRoundTowardMinusInfinity) {
  EXPECT_EQ(Stamp::from_ns(1999)->us(), 1);
  EXPECT_EQ(Stamp::from_ns(-1)->us(), -1);
  EXPECT_EQ(Stamp::from_ns(-1000)->us(), -1);
  EXPECT_EQ(Stamp::from_ns(-1001)->us(), -2);
  EXPECT_EQ(Stamp::from_ns(-kLimit)->us(), -kLimit / 1000 - 1);  // 2^61 is not a multiple of 1000
}

TEST(Stamp, MovedFarOutIsRefusedNeverWrapped) {
  const Stamp top = *Stamp::from_ns(kLimit), bottom = *Stamp::from_ns(-kLimit);
  EXPECT_FALSE(top.plus_ns(1));
  EXPECT_FALSE(top.plus_ns(INT64_MAX));  // would overflow int64 itself
  EXPECT_FALSE(bottom.plus_ns(INT64_MIN));
  EXPECT_EQ(top.plus_ns(-2 * kLimit)->ns(), -kLimit);
  EXPECT_EQ(top - bottom, 2 * kLimit);  // exact
  EXPECT_FALSE(top.plus_s(1e300));
  EXPECT_FALSE(top.plus_s(std::nan("")));
  EXPECT_EQ(Stamp::from_ns(5)->plus_s(-1e-9)->ns(), 4);
}

TEST(Stamp, EveryCombinationAgreesWithWideArithmetic) {
  std::mt19937_64 rng(7);
  const int64_t extremes[] = {INT64_MIN, INT64_MIN + 1, -kLimit - 1, -kLimit, -1, 0, 1, kLimit, kLimit + 1, INT64_MAX};
  auto pick = [&](int i) { return i % 3 == 0 ? extremes[rng() % 10] : static_cast<int64_t>(rng()) >> (rng() % 64); };
  for (int i = 0; i < 200000; ++i) {
    const int64_t a = pick(i), d = pick(i + 1);
    const __int128 wide = static_cast<__int128>(a) + d;
    const std::optional<Stamp> s = Stamp::from_ns(a);
    ASSERT_EQ(s.has_value(), a >= -kLimit && a <= kLimit) << a;
    if (!s) continue;
    const std::optional<Stamp> m = s->plus_ns(d);
    ASSERT_EQ(m.has_value(), wide >= -kLimit && wide <= kLimit) << a << " + " << d;
    if (!m) continue;
    ASSERT_EQ(static_cast<__int128>(m->ns()), wide);
    ASSERT_EQ(static_cast<__int128>(*m - *s), static_cast<__int128>(m->ns()) - a);
  }
}
