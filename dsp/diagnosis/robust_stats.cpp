#include "dsp/diagnosis/robust_stats.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

#include "dsp/core/statistics.hpp"

namespace rsd::dsp {

RobustStats robust_stats(const std::vector<Eigen::Vector2d>& residuals) {
  RobustStats s;
  s.observations = static_cast<int>(residuals.size());
  std::vector<double> len;
  for (const auto& r : residuals)
    if (r.allFinite()) len.push_back(r.norm());
  if (len.empty()) {
    s.outliers = s.observations;
    return s;
  }
  // Median of a Rayleigh(sigma) length is sigma sqrt(2 ln 2); outliers push the median up
  // (10% of them by 8%), so refine it by the RMS of the lengths within 3 scales, corrected for
  // the truncation: E[l^2 | l < 3 sigma] = 2 sigma^2 g, g = (1 - 5.5 e^-4.5) / (1 - e^-4.5).
  s.scale_px = median(len) / std::sqrt(2 * std::log(2.0));
  const double g = (1 - 5.5 * std::exp(-4.5)) / (1 - std::exp(-4.5));
  for (int it = 0; it < 5 && s.scale_px > 0; ++it) {
    double sum2 = 0;
    int n = 0;
    for (double l : len)
      if (l <= 3 * s.scale_px) sum2 += l * l, ++n;
    if (n < 3) break;
    s.scale_px = std::sqrt(sum2 / (2.0 * n * g));
  }
  const double limit = kOutlierSigmas * std::max(s.scale_px, 1e-12);
  double sum = 0;
  int n = 0;
  for (double l : len)
    if (l <= limit) sum += l * l, ++n;
  s.outliers = s.observations - n;
  s.rms_px = n > 0 ? std::sqrt(sum / (2.0 * n)) : 0.0;
  return s;
}

std::vector<bool> inliers(const std::vector<Eigen::Vector2d>& r) {
  const RobustStats s = robust_stats(r);
  std::vector<bool> in(r.size());
  for (size_t k = 0; k < r.size(); ++k) in[k] = r[k].allFinite() && r[k].norm() <= kOutlierSigmas * s.scale_px;
  return in;
}

PairedChange paired_change(const std::vector<Eigen::Vector2d>& before, const std::vector<Eigen::Vector2d>& after,
                           const std::vector<int>& group) {
  const double limit = kOutlierSigmas * robust_stats(before).scale_px;
  std::map<int, double> sum_of;
  for (size_t k = 0; k < before.size(); ++k)
    if (before[k].allFinite() && after[k].allFinite() && before[k].norm() <= limit && after[k].norm() <= limit)
      sum_of[group[k]] += after[k].squaredNorm() - before[k].squaredNorm();
  PairedChange c;
  c.groups = static_cast<int>(sum_of.size());
  if (c.groups < 3) return c;
  double sum = 0, sum2 = 0;
  for (const auto& [g, d] : sum_of) sum += d, sum2 += d * d;
  const double n = c.groups;
  c.mean = sum / n;
  const double se = std::sqrt(std::max(sum2 / n - c.mean * c.mean, 0.0) / (n - 1));
  // A spread below rounding is none: every group changed alike.
  const bool alike = se <= 1e-12 * std::max(std::abs(c.mean), 1e-300);
  c.t = !alike ? c.mean / se : c.mean > 0 ? std::numeric_limits<double>::infinity()
                             : c.mean < 0 ? -std::numeric_limits<double>::infinity() : 0.0;
  return c;
}

}  // namespace rsd::dsp
