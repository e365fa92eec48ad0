#include "dsp/diagnosis/clock_shape.hpp"

#include <algorithm>
#include <cmath>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/fit.hpp"
#include "dsp/diagnosis/uncertainty.hpp"

namespace rsd::dsp {

namespace {

// idx cut into windows of equal length in frame time.
std::vector<std::vector<int>> time_windows(const DiagnosisModel& m, const std::vector<int>& idx) {
  if (idx.empty()) return {};
  double first = m.frame_time(idx.front()), last = first;
  for (int i : idx) first = std::min(first, m.frame_time(i)), last = std::max(last, m.frame_time(i));
  const int n = std::clamp(static_cast<int>((last - first) / kClockWindowS), 0, kClockWindows);
  if (n < 1) return {};
  std::vector<std::vector<int>> out(static_cast<size_t>(n));
  const double length = (last - first) / n;
  for (int i : idx) out[std::min(n - 1, static_cast<int>((m.frame_time(i) - first) / length))].push_back(i);
  return out;
}

}  // namespace

ClockShape clock_shape(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx, double sigma_px) {
  constexpr size_t kMinObservations = 50;
  constexpr int kIterations = 10;
  ParamMask offset_only;
  offset_only.set(static_cast<size_t>(Param::TimeOffset));
  const double t0 = m.recording().nominal.time.t0;
  ClockShape out;
  for (const std::vector<int>& w : time_windows(m, idx)) {
    if (w.size() < kMinObservations) continue;
    std::vector<double> t;
    for (int i : w) t.push_back(m.frame_time(i));
    const double mid = median(std::move(t));
    const ModelParams q = fit_params(m, w, p, offset_only, sigma_px, kIterations);
    const auto var = parameter_variances(m, q, {Param::TimeOffset}, w);
    if (!var || !((*var)[0] > 0)) continue;
    out.windows.push_back({mid, q[Param::TimeOffset] + q[Param::Drift] * 1e-6 * (mid - t0), (*var)[0]});
  }
  out.verdict = line_or_step(out.windows);
  return out;
}

}  // namespace rsd::dsp
