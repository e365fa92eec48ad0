#include "dsp/core/line_or_step.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rsd::dsp {

namespace {

bool usable(const TimedValue& x) { return std::isfinite(x.t) && std::isfinite(x.value) && x.variance > 0; }

// The weighted mean of v[first, last) and the chi-square about it (0 values: NaN mean).
std::pair<double, double> level(const std::vector<TimedValue>& v, size_t first, size_t last) {
  double w = 0, s = 0;
  for (size_t k = first; k < last; ++k) w += 1 / v[k].variance, s += v[k].value / v[k].variance;
  const double mean = s / w;
  double chi2 = 0;
  for (size_t k = first; k < last; ++k) chi2 += (v[k].value - mean) * (v[k].value - mean) / v[k].variance;
  return {mean, chi2};
}

}  // namespace

WeightedLine fit_line(const std::vector<TimedValue>& v, double t_ref) {
  WeightedLine l;
  l.t_ref = t_ref;
  Eigen::Matrix2d N = Eigen::Matrix2d::Zero();
  Eigen::Vector2d b = Eigen::Vector2d::Zero();
  for (const TimedValue& x : v) {
    if (!usable(x)) return l;
    const Eigen::Vector2d a(1.0, x.t - t_ref);
    N += a * a.transpose() / x.variance, b += a * x.value / x.variance;
  }
  const Eigen::FullPivLU<Eigen::Matrix2d> lu(N);
  if (v.size() < 2 || !lu.isInvertible()) return l;
  const Eigen::Vector2d line = lu.solve(b);
  l.at = line[0], l.slope = line[1], l.covariance = lu.inverse();
  for (const TimedValue& x : v) {
    const double z = (x.value - l(x.t)) / std::sqrt(x.variance);
    l.chi2 += z * z, l.worst_sigmas = std::max(l.worst_sigmas, std::abs(z));
  }
  l.valid = line.allFinite();
  return l;
}

WeightedStep fit_step(const std::vector<TimedValue>& v) {
  WeightedStep best;
  best.chi2 = std::numeric_limits<double>::infinity();
  if (!std::all_of(v.begin(), v.end(), usable)) return best;
  // Value `aside` is the one set aside: levels over [0, aside) and (aside, n).
  for (size_t aside = 2; aside + 2 < v.size(); ++aside) {
    const auto [before, chi_before] = level(v, 0, aside);
    const auto [after, chi_after] = level(v, aside + 1, v.size());
    if (chi_before + chi_after >= best.chi2) continue;
    best = {v[aside].t, before, after, chi_before + chi_after, true};
  }
  return best;
}

LineOrStep line_or_step(const std::vector<TimedValue>& v) {
  constexpr size_t kMinValues = 6;
  constexpr double kClearSigmas = 4.0, kStepShare = 0.25;
  LineOrStep r;
  if (v.size() < kMinValues) return r;
  r.line = fit_line(v, v.front().t);
  r.step = fit_step(v);
  if (!r.line.valid || !r.step.valid) return r;
  const double dof = static_cast<double>(v.size()) - 2;
  const bool line_misfits = r.line.chi2 > dof + kClearSigmas * std::sqrt(2 * dof);
  r.is_step = line_misfits && r.step.chi2 <= kStepShare * r.line.chi2;
  return r;
}

}  // namespace rsd::dsp
