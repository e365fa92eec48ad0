// Line or step (dsp/core/line_or_step.hpp) against cases worked by hand and by brute force: the
// weighted line against the normal equations written out in sums, the step against every split
// tried by a plain loop; a drift called a line, a jump a step, a wandering misfit neither, and
// errors understated by a common factor leave the verdict as it was.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "dsp/core/line_or_step.hpp"

using namespace rsd::dsp;

namespace {

// A deterministic scatter of about unit size (no generator: the numbers are the test's).
double wobble(int k) { return std::sin(1.7 * k + 0.3) * 1.2; }

std::vector<TimedValue> series(int n, double variance, double (*shape)(double)) {
  std::vector<TimedValue> v;
  for (int k = 0; k < n; ++k) {
    const double t = 100.0 + 0.5 * k;
    v.push_back({t, shape(t) + std::sqrt(variance) * wobble(k), variance});
  }
  return v;
}

}  // namespace

TEST(LineOrStep, TheLineIsTheWeightedLeastSquaresOne) {
  // Unequal weights; the closed form from the sums S, Sx, Sy, Sxx, Sxy (x = t - t_ref).
  const std::vector<TimedValue> v = {{1, 2.0, 0.5}, {2, 2.9, 1.0}, {4, 5.2, 2.0}, {5, 6.1, 0.25}, {7, 7.7, 1.5}};
  const double t_ref = 3;
  double S = 0, Sx = 0, Sy = 0, Sxx = 0, Sxy = 0;
  for (const TimedValue& x : v) {
    const double w = 1 / x.variance, d = x.t - t_ref;
    S += w, Sx += w * d, Sy += w * x.value, Sxx += w * d * d, Sxy += w * d * x.value;
  }
  const double det = S * Sxx - Sx * Sx;
  const double slope = (S * Sxy - Sx * Sy) / det, at = (Sxx * Sy - Sx * Sxy) / det;
  const WeightedLine l = fit_line(v, t_ref);
  ASSERT_TRUE(l.valid);
  EXPECT_NEAR(l.slope, slope, 1e-12);
  EXPECT_NEAR(l.at, at, 1e-12);
  EXPECT_NEAR(l.covariance(1, 1), S / det, 1e-12);  // the slope's variance
  EXPECT_NEAR(l.covariance(0, 0), Sxx / det, 1e-12);
  double chi2 = 0, worst = 0;
  for (const TimedValue& x : v) {
    const double z = (x.value - at - slope * (x.t - t_ref)) / std::sqrt(x.variance);
    chi2 += z * z, worst = std::max(worst, std::abs(z));
  }
  EXPECT_NEAR(l.chi2, chi2, 1e-9);
  EXPECT_NEAR(l.worst_sigmas, worst, 1e-9);
}

TEST(LineOrStep, TheStepIsTheBestSplitWithOneValueAside) {
  const std::vector<TimedValue> v = series(12, 0.04, [](double t) { return t < 103.2 ? 1.0 : 4.0; });
  const WeightedStep s = fit_step(v);
  ASSERT_TRUE(s.valid);
  // Brute force: every split, plain means (equal weights), one value set aside.
  double best = std::numeric_limits<double>::infinity(), at = 0;
  for (size_t aside = 2; aside + 2 < v.size(); ++aside) {
    double chi2 = 0;
    for (auto [first, last] : {std::pair<size_t, size_t>{0, aside}, {aside + 1, v.size()}}) {
      double mean = 0;
      for (size_t k = first; k < last; ++k) mean += v[k].value / static_cast<double>(last - first);
      for (size_t k = first; k < last; ++k) chi2 += (v[k].value - mean) * (v[k].value - mean) / 0.04;
    }
    if (chi2 < best) best = chi2, at = v[aside].t;
  }
  EXPECT_NEAR(s.chi2, best, 1e-9);
  EXPECT_EQ(s.at, at);
  EXPECT_NEAR(s.after - s.before, 3.0, 0.3);
  EXPECT_NEAR(s.at, 103.2, 0.5);
}

TEST(LineOrStep, ADriftIsALineAndAJumpAStep) {
  const auto drift = line_or_step(series(10, 0.01, [](double t) { return 0.4 * (t - 100); }));
  EXPECT_FALSE(drift.is_step);
  EXPECT_NEAR(drift.line.slope, 0.4, 0.05);
  const auto jump = line_or_step(series(10, 0.01, [](double t) { return t < 102.3 ? 0.0 : 3.0; }));
  EXPECT_TRUE(jump.is_step) << "line chi2 " << jump.line.chi2 << ", step chi2 " << jump.step.chi2;
  EXPECT_NEAR(jump.step.after - jump.step.before, 3.0, 0.2);
  // The same jump under errors four times the stated ones (stated 0.01, scatter 0.16): a step still.
  std::vector<TimedValue> loose = series(10, 0.16, [](double t) { return t < 102.3 ? 0.0 : 3.0; });
  for (TimedValue& x : loose) x.variance = 0.01;
  EXPECT_TRUE(line_or_step(loose).is_step);
}

TEST(LineOrStep, AMisfitThatWandersIsNotAStep) {
  // A drift seen through a model not quite right: the values wander about the line by ten of
  // their sigmas. The line misfits, but a step does no better.
  const auto r = line_or_step(series(16, 0.01, [](double t) { return 0.2 * (t - 100) + std::sin(2.1 * t); }));
  EXPECT_GT(r.line.chi2, 100);
  EXPECT_FALSE(r.is_step) << "line chi2 " << r.line.chi2 << ", step chi2 " << r.step.chi2;
}

TEST(LineOrStep, AJumpWithinTheNoiseIsNotCalledAStep) {
  EXPECT_FALSE(line_or_step(series(10, 1.0, [](double t) { return t < 102.3 ? 0.0 : 0.5; })).is_step);
}

TEST(LineOrStep, TooFewOrUnusableValuesGiveNoVerdict) {
  const auto few = line_or_step(series(5, 0.01, [](double t) { return t < 101 ? 0.0 : 3.0; }));
  EXPECT_FALSE(few.is_step);
  std::vector<TimedValue> bad = series(10, 0.01, [](double t) { return t < 102.3 ? 0.0 : 3.0; });
  bad[4].variance = 0;
  EXPECT_FALSE(fit_line(bad, 100).valid);
  EXPECT_FALSE(fit_step(bad).valid);
  EXPECT_FALSE(line_or_step(bad).is_step);
  bad[4].variance = 0.01, bad[6].value = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(line_or_step(bad).is_step);
}
