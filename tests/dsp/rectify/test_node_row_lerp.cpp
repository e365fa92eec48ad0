// The map's per-row interpolation of node columns (node_row_lerp.hpp) on every instruction set
// this CPU runs, against the scalar reference (the same doubles and 16.16 values, bit for bit),
// and the reference against exact arithmetic (long double) and the rounding rule of to_fixed.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "dsp/rectify/bilinear_sampling.hpp"
#include "dsp/rectify/fixed_point.hpp"
#include "dsp/rectify/node_row_lerp.hpp"
#include "tests/dsp/rectify/simd_targets.hpp"

using namespace rsd::dsp::rectify_detail;
using namespace rsd::dsp::test;

namespace {

struct Row {
  std::vector<double> top, bot;
};

// Node values as the map has them: positions within +-8192 px, some exactly on a 1/131072 tie
// (where the rounding direction shows), negative ones, and a NaN (an unsolved node).
Row random_row(std::mt19937& rng, int n) {
  std::uniform_real_distribution<double> pos(-3000, 3000);
  Row r{std::vector<double>(n), std::vector<double>(n)};
  for (int i = 0; i < n; ++i) r.top[i] = pos(rng), r.bot[i] = r.top[i] + pos(rng) / 100;
  if (n > 3) r.top[1] = r.bot[1] = -2.5 / 65536, r.top[2] = r.bot[2] = 7.5 / 65536;  // ties
  if (n > 5) r.bot[4] = std::nan("");
  return r;
}

TEST_F(EveryTarget, ComputesTheReferenceDoublesAndFixedValues) {
  std::mt19937 rng(5);
  for_every_target([&](std::int64_t target) {
    for (int n : {1, 2, 3, 7, 8, 9, 16, 31, 61, 121}) {
      const Row r = random_row(rng, n);
      const double w = std::uniform_real_distribution<double>(0, 1)(rng);
      std::vector<double> got(n + 1, -7), want(n + 1, -7);
      std::vector<std::int32_t> gfix(n + 1, 99), wfix(n + 1, 99);
      lerp_node_row(r.top.data(), r.bot.data(), w, n, got.data(), gfix.data());
      lerp_node_row_scalar(r.top.data(), r.bot.data(), w, n, want.data(), wfix.data());
      for (int i = 0; i < n; ++i) {
        const std::string where = target_name(target) + " n " + std::to_string(n) + " node " + std::to_string(i);
        EXPECT_EQ(std::memcmp(&got[i], &want[i], sizeof(double)), 0) << where << ": " << got[i] << " vs " << want[i];
        EXPECT_EQ(gfix[i], wfix[i]) << where;  // the NaN's too: kSentinel on every target
      }
      EXPECT_EQ(got[n], -7) << "wrote past the row";
      EXPECT_EQ(gfix[n], 99) << "wrote past the row";
      std::vector<double> only(n + 1, -7);  // without fixed values: the doubles alone
      lerp_node_row(r.top.data(), r.bot.data(), w, n, only.data(), nullptr);
      EXPECT_EQ(std::memcmp(only.data(), want.data(), n * sizeof(double)), 0) << target_name(target);
    }
  });
}

TEST(Reference, IsTheLinearInterpolationRoundedHalfAwayFromZero) {
  std::mt19937 rng(9);
  const Row r = random_row(rng, 64);
  const double w = 0.3125;
  std::vector<double> out(64);
  std::vector<std::int32_t> fix(64);
  lerp_node_row_scalar(r.top.data(), r.bot.data(), w, 64, out.data(), fix.data());
  for (int i = 0; i < 64; ++i) {
    if (!std::isfinite(out[i])) continue;
    const long double exact = r.top[i] + static_cast<long double>(w) * (r.bot[i] - r.top[i]);
    EXPECT_NEAR(static_cast<double>(out[i] - exact), 0.0, 1e-12) << i;
    const long double scaled = exact * 65536;
    const long double want = scaled < 0 ? -std::floor(-scaled + 0.5L) : std::floor(scaled + 0.5L);
    EXPECT_EQ(fix[i], static_cast<std::int32_t>(want)) << i << ": " << out[i];
  }
  EXPECT_EQ(fix[1], -3);  // -2.5 / 65536 px: half away from zero
  EXPECT_EQ(fix[2], 8);
  EXPECT_EQ(fix[4], kSentinel);  // the unsolved node: no 16.16 value (a NaN cast to int is undefined)
  EXPECT_EQ(to_fixed(kLimit), static_cast<std::int32_t>(kLimit * kFix));
  EXPECT_EQ(to_fixed(-kLimit - 1), kSentinel);
  EXPECT_EQ(to_fixed(1e300), kSentinel);
}

}  // namespace
