// paired_change: the paired comparison of two models' residuals over groups of observations that
// move together (dsp/diagnosis/robust_stats.hpp), against cases worked by hand.
#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cmath>
#include <limits>
#include <vector>

#include "dsp/diagnosis/robust_stats.hpp"

namespace rsd::test {
namespace {

using dsp::paired_change;
using dsp::PairedChange;

// Unit residuals before; after, one observation per group whose squared length grows by
// 1, 2, 3, 4, 5 px^2.
struct Residuals {
  std::vector<Eigen::Vector2d> before, after;
  std::vector<int> group;
};
Residuals one_per_group() {
  Residuals r;
  for (int k = 0; k < 5; ++k) {
    r.before.emplace_back(1, 0);
    r.after.emplace_back(std::sqrt(1.0 + (k + 1)), 0);
    r.group.push_back(k);
  }
  return r;
}

// one_per_group: the mean change 3, the sample deviation sqrt(2.5), the standard error
// sqrt(2.5 / 5) = sqrt(0.5), t = 3 / sqrt(0.5).
TEST(PairedChange, OneObservationPerGroupGivesTheTextbookPairedT) {
  auto [before, after, group] = one_per_group();
  const PairedChange c = paired_change(before, after, group);
  EXPECT_EQ(c.groups, 5);
  EXPECT_NEAR(c.mean, 3.0, 1e-12);
  EXPECT_NEAR(c.t, 3.0 / std::sqrt(0.5), 1e-9);
  // The other way round: as much better.
  EXPECT_NEAR(paired_change(after, before, group).t, -3.0 / std::sqrt(0.5), 1e-9);
}

// A group's observations are summed before the test: four groups of three observations each,
// every observation of group g changing by g + 1 px^2 (the sums 3, 6, 9, 12: mean 7.5, sample
// deviation sqrt(15), standard error sqrt(15 / 4)). Counted one by one the same changes would
// give a t nearly twice as large (7.4): the pairing is what keeps a pair's shared shift from counting thrice.
TEST(PairedChange, ObservationsOfAGroupAreOneSample) {
  std::vector<Eigen::Vector2d> before, after;
  std::vector<int> group;
  for (int g = 0; g < 4; ++g)
    for (int i = 0; i < 3; ++i) {
      before.emplace_back(0, 1);
      after.emplace_back(0, std::sqrt(1.0 + (g + 1)));
      group.push_back(10 * g);  // any labels
    }
  const PairedChange c = paired_change(before, after, group);
  EXPECT_EQ(c.groups, 4);
  EXPECT_NEAR(c.mean, 7.5, 1e-12);
  EXPECT_NEAR(c.t, 7.5 / std::sqrt(15.0 / 4.0), 1e-9);
}

// An observation either model puts beyond kOutlierSigmas robust scales of `before` (here 100 px
// where the rest lie within 2.5 px), or fails to predict (NaN), has no say.
TEST(PairedChange, OutliersAndFailedPredictionsHaveNoSay) {
  auto [before, after, group] = one_per_group();
  before.emplace_back(1, 0), after.emplace_back(100, 0), group.push_back(0);
  before.emplace_back(std::numeric_limits<double>::quiet_NaN(), 0), after.emplace_back(1, 0), group.push_back(1);
  const PairedChange c = paired_change(before, after, group);
  EXPECT_NEAR(c.mean, 3.0, 1e-12);
  EXPECT_NEAR(c.t, 3.0 / std::sqrt(0.5), 1e-9);
}

// Every group worse by the same amount: no spread, as sure as it gets; no change at all: 0; and
// fewer than three groups cannot be judged.
TEST(PairedChange, EdgeCases) {
  std::vector<Eigen::Vector2d> before(6, Eigen::Vector2d(1, 0)), after(6, Eigen::Vector2d(1.5, 0));
  const std::vector<int> group = {0, 1, 2, 3, 4, 5};
  EXPECT_EQ(paired_change(before, after, group).t, std::numeric_limits<double>::infinity());
  EXPECT_EQ(paired_change(after, before, group).t, -std::numeric_limits<double>::infinity());
  EXPECT_EQ(paired_change(before, before, group).t, 0.0);
  const PairedChange two = paired_change(before, after, {0, 0, 0, 1, 1, 1});
  EXPECT_EQ(two.groups, 2);
  EXPECT_EQ(two.t, 0.0);
}

}  // namespace
}  // namespace rsd::test
