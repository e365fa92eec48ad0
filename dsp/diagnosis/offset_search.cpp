#include "dsp/diagnosis/offset_search.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>

namespace rsd::dsp {

namespace {

// Truncated quadratic cost: bounded per observation so that a wrong offset (residuals of
// hundreds of pixels) costs the same wherever it is, and the valley is clear.
double truncated_cost(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double width_px) {
  double c = 0;
  for (const auto& r : m.residuals(p, idx))
    c += r.allFinite() ? std::min(r.squaredNorm() / (width_px * width_px), 1.0) : 1.0;
  return c;
}

struct GridBest {
  double offset, cost;
};

GridBest best_offset(const DiagnosisModel& m, const std::vector<int>& idx, ModelParams p, double lo, double hi,
                     double step, double width_px) {
  GridBest best{p[Param::TimeOffset], std::numeric_limits<double>::infinity()};
  for (double t = lo; t <= hi + 1e-12; t += step) {
    p[Param::TimeOffset] = t;
    const double c = truncated_cost(m, idx, p, width_px);
    if (c < best.cost) best = {t, c};
  }
  return best;
}

std::pair<double, double> search_range(const DiagnosisModel& m, double now) {
  const auto [lo, hi] = m.offset_range();
  return {std::max(lo, now - 1.0), std::min(hi, now + 1.0)};
}

// Coarse width: 20 sigma, or 2% of the image width when that is more, so that what the
// coarse grid cannot resolve (half a 5 ms step of motion, a 2.5% focal error, an unmodelled
// readout) still counts as "near".
double coarse_width(const DiagnosisModel& m, double sigma) {
  return std::max(20 * sigma, 0.02 * m.recording().nominal.cam.width);
}

}  // namespace

double refine_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma,
                          double half_width_s) {
  const auto [lo, hi] = search_range(m, p[Param::TimeOffset]);
  const double now = p[Param::TimeOffset];
  if (!(lo < hi)) return now;
  return best_offset(m, idx, p, std::max(lo, now - half_width_s), std::min(hi, now + half_width_s), 2.5e-4,
                     5 * sigma).offset;
}

double settle_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma) {
  const auto [lo, hi] = search_range(m, p[Param::TimeOffset]);
  const double now = p[Param::TimeOffset], half = 2.0 / m.recording().nominal.frame_rate_hz;
  if (!(lo < hi)) return now;
  const GridBest grid = best_offset(m, idx, p, std::max(lo, now - half), std::min(hi, now + half), 2.5e-3, 5 * sigma);
  if (!(grid.cost < truncated_cost(m, idx, p, 5 * sigma))) return now;
  ModelParams q = p;
  q[Param::TimeOffset] = grid.offset;
  const double settled = refine_time_offset(m, idx, q, sigma, 2.5e-3);
  // A rolling shutter left out moves the best offset by half its readout, at most half a frame
  // period: that is the shutter's to explain, judged as itself (under a translation nuisance an
  // offset started there stood in for it). Beyond, the grid missed the clock.
  return std::abs(settled - now) > 0.5 / m.recording().nominal.frame_rate_hz ? settled : now;
}

double scan_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma) {
  const std::vector<int> sub = subsample(idx, 150);
  const auto [lo, hi] = search_range(m, p[Param::TimeOffset]);
  if (!(lo < hi)) return p[Param::TimeOffset];
  ModelParams q = p;
  q[Param::TimeOffset] = best_offset(m, sub, p, lo, hi, 5e-3, coarse_width(m, sigma)).offset;
  return refine_time_offset(m, sub, q, sigma);
}

double profile_time_offset(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma,
                           double step_s) {
  const double now = p[Param::TimeOffset];
  if (!(step_s > 0) || !std::isfinite(step_s)) return now;
  constexpr int kHalf = 4;  // points either side: four steps
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  ModelParams q = p;
  for (int k = -kHalf; k <= kHalf; ++k) {
    q[Param::TimeOffset] = now + k * step_s;
    const double cost = robust_chi2(m.residuals(q, idx), sigma);
    if (!std::isfinite(cost)) return now;
    const Eigen::Vector3d basis(1.0, k, static_cast<double>(k) * k);  // in steps
    normal += basis * basis.transpose();
    rhs += basis * cost;
  }
  const Eigen::Vector3d c = normal.ldlt().solve(rhs);
  if (!(c[2] > 0)) return now;  // no minimum: the trend falls or is flat
  return now + std::clamp(-c[1] / (2 * c[2]), -static_cast<double>(kHalf), static_cast<double>(kHalf)) * step_s;
}

ModelParams gross_start(const DiagnosisModel& m, const std::vector<int>& idx, const ModelParams& p, double sigma,
                        const std::function<void(int, int)>& step) {
  const std::vector<int> sub = subsample(idx, p.translation_nuisance ? 600 : 150);
  const auto [lo, hi] = search_range(m, p[Param::TimeOffset]);
  ModelParams start = p;
  start.translation_pair_shifts = false;  // ModelParams: one observation a pair here
  ModelParams best = start;
  double best_cost = std::numeric_limits<double>::infinity();
  // Nominal focal first, then outwards: a recording that does not see the focal length (a
  // flat cost) keeps the nominal one.
  constexpr int kScales[] = {0, -1, 1, -2, 2, -3, 3, -4, 4};
  int done = 0;
  for (int k : kScales) {
    ModelParams q = start;
    q[Param::Fx] *= 1 + 0.05 * k;
    q[Param::Fy] *= 1 + 0.05 * k;
    const GridBest g = lo < hi ? best_offset(m, sub, q, lo, hi, 5e-3, coarse_width(m, sigma))
                               : GridBest{q[Param::TimeOffset], truncated_cost(m, sub, q, coarse_width(m, sigma))};
    if (g.cost < best_cost) {
      best_cost = g.cost;
      best = q;
      best[Param::TimeOffset] = g.offset;
    }
    if (step) step(++done, static_cast<int>(std::size(kScales)));
  }
  if (lo < hi) best[Param::TimeOffset] = refine_time_offset(m, sub, best, sigma);
  best.translation_pair_shifts = p.translation_pair_shifts;
  return best;
}

}  // namespace rsd::dsp
