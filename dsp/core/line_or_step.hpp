// Values measured over time, each with its variance (a clock's offset, fitted window by window):
// do they follow a straight line, or a step? A clock that drifts runs at a rate, and its offset
// grows along a line; a clock that jumps holds one offset, then another. A line can stand in for
// a step (a 3 ms jump half-way through ten seconds is three quarters of a 380 ppm drift), so the
// choice is made on the values themselves: weighted least squares of each shape, compared by
// chi-square. Pure arithmetic; used by the diagnosis (clock_drift must be a rate) and by the
// online estimator (a drift starts only from offsets on a line).
#pragma once

#include <Eigen/Core>
#include <vector>

namespace rsd::dsp {

struct TimedValue {
  double t = 0, value = 0, variance = 0;
};

// The weighted least-squares line value(t) = at + slope (t - t_ref), weights 1 / variance.
struct WeightedLine {
  double t_ref = 0, at = 0, slope = 0;
  Eigen::Matrix2d covariance = Eigen::Matrix2d::Zero();  // of (at, slope)
  double chi2 = 0;          // sum of squared deviations over variances
  double worst_sigmas = 0;  // the largest |deviation| / sqrt(variance)
  bool valid = false;       // at least two distinct times and positive variances
  double operator()(double t) const { return at + slope * (t - t_ref); }
};
WeightedLine fit_line(const std::vector<TimedValue>& v, double t_ref);

// The best step: one level before it, another after, with the value whose time lies nearest the
// change set aside (a window that straddles the change measures neither level); `at` is that
// value's time.
struct WeightedStep {
  double at = 0, before = 0, after = 0;
  double chi2 = 0;
  bool valid = false;  // at least two values on each side of the one set aside
};
WeightedStep fit_step(const std::vector<TimedValue>& v);

// The verdict: a step, not a line, when the line does not fit the values (its chi-square beyond
// four standard deviations of its degrees of freedom' distribution) and the step takes at least
// three quarters of that chi-square away. A misfit that merely wanders (a model not quite the
// camera's) spoils a step as much as a line, and errors understated by a common factor scale both
// chi-squares alike: neither makes a step of a rate. Needs six values or more (values ordered by t).
struct LineOrStep {
  WeightedLine line;
  WeightedStep step;
  bool is_step = false;
};
LineOrStep line_or_step(const std::vector<TimedValue>& v);

}  // namespace rsd::dsp
