// locate(): where the residual of a model lives. Each signal is a set of residual patterns,
// and its strength the share of the inlier residual energy that a least-squares fit of the
// patterns explains. The patterns are the model's own derivatives (what a small change of
// the time offset, line delay, distortion, focal length, gyro bias or drift does to every
// residual), so they mean the same for landmarks and matches: for a match the time-offset
// pattern follows the change of the image motion over the frame interval (the angular
// acceleration), the line-delay pattern follows it row by row. Signals: image_velocity (time
// offset), row (line delay), column (a delay across the columns), radius (k1, k2), image_scale (fx, fy), time_trend (drift beyond
// a constant offset), time (energy concentrated in a span of frames), fast_rotation (energy
// concentrated in the frames of fastest rotation: a gyro that clips; gyro recordings),
// angular_rate (gyro bias; gyro recordings), depth (lever arm; trajectory recordings).
#include <Eigen/Dense>
#include <algorithm>
#include <sstream>

#include "dsp/core/statistics.hpp"
#include "dsp/diagnosis/locate.hpp"
#include "dsp/diagnosis/robust_stats.hpp"
#include "dsp/diagnosis/fit.hpp"

namespace rsd::dsp {

namespace {

// Share of the energy of r that the columns of A explain (least squares R^2 about zero).
double explained(const Eigen::MatrixXd& A, const Eigen::VectorXd& r) {
  const double e = r.squaredNorm();
  if (e <= 0 || A.rows() <= A.cols()) return 0;
  const Eigen::VectorXd beta = A.colPivHouseholderQr().solve(r);
  return std::clamp(1.0 - (r - A * beta).squaredNorm() / e, 0.0, 1.0);
}

struct Patterns {
  std::vector<int> keep;  // positions in idx of the inliers
  Eigen::VectorXd r;      // their stacked (du, dv) residuals
  std::vector<std::pair<int, double>> frame_energy;  // (frame rank, |r|^2)
};

Patterns inlier_patterns(const DiagnosisModel& m, const std::vector<Eigen::Vector2d>& base, const std::vector<int>& idx) {
  const RobustStats st = robust_stats(base);
  Patterns s;
  for (size_t k = 0; k < idx.size(); ++k)
    if (base[k].allFinite() && base[k].norm() <= kOutlierSigmas * st.scale_px) s.keep.push_back(static_cast<int>(k));
  s.r.resize(2 * s.keep.size());
  for (size_t j = 0; j < s.keep.size(); ++j) {
    s.r.segment<2>(2 * j) = base[s.keep[j]];
    s.frame_energy.push_back({m.frame_rank(idx[s.keep[j]]), base[s.keep[j]].squaredNorm()});
  }
  return s;
}

// d(residual)/d(parameter) for the inliers, one column per parameter, in param_scale units.
Eigen::MatrixXd derivatives(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx,
                            const std::vector<Eigen::Vector2d>& base, const Patterns& s, std::vector<Param> params) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(s.r.size(), static_cast<int>(params.size()));
  for (size_t c = 0; c < params.size(); ++c) {
    ModelParams q = p;
    const double h = 0.1 * param_scale(params[c], m.recording().nominal);
    q[params[c]] += h;
    const auto r = m.residuals(q, idx);
    for (size_t j = 0; j < s.keep.size(); ++j) {
      const int k = s.keep[j];
      if (r[k].allFinite()) A.block<2, 1>(2 * j, static_cast<int>(c)) = (r[k] - base[k]) / 0.1;
    }
  }
  return A;
}

// The time-shift pattern (column 0 of A) weighted by each inlier's image column, centred
// and as a share of the width: a delay growing across the columns, as a sensor read out
// column by column (mounted a quarter turn from its nominal orientation) would give.
Eigen::MatrixXd column_pattern(const DiagnosisModel& m, const std::vector<int>& idx, const Patterns& s,
                               const Eigen::MatrixXd& A) {
  const CameraModel& cam = m.recording().nominal.cam;
  Eigen::MatrixXd out(A.rows(), 1);
  for (size_t j = 0; j < s.keep.size(); ++j) {
    const double c = (m.observed(idx[s.keep[j]]).x() - cam.cx) / cam.width;
    out.block<2, 1>(2 * j, 0) = A.block<2, 1>(2 * j, 0) * c;
  }
  return out;
}

Eigen::MatrixXd columns(const Eigen::MatrixXd& A, std::vector<int> cols) {
  Eigen::MatrixXd out(A.rows(), static_cast<int>(cols.size()));
  for (size_t c = 0; c < cols.size(); ++c) out.col(static_cast<int>(c)) = A.col(cols[c]);
  return out;
}

// Each frame's residual energy (sum, count) by rank.
struct FrameEnergy {
  int rank;
  double sum = 0, count = 0;
  double mean() const { return sum / count; }
};
std::vector<FrameEnergy> frame_energies(const std::vector<std::pair<int, double>>& fe) {
  std::vector<FrameEnergy> out;
  std::vector<int> at;
  for (const auto& [rank, e] : fe) {
    if (rank >= static_cast<int>(at.size())) at.resize(rank + 1, -1);
    if (at[rank] < 0) at[rank] = static_cast<int>(out.size()), out.push_back({rank});
    out[at[rank]].sum += e, out[at[rank]].count += 1;
  }
  std::sort(out.begin(), out.end(), [](const FrameEnergy& a, const FrameEnergy& b) { return a.rank < b.rank; });
  return out;
}

// The "hot" frames: mean energy beyond 4x the median frame's.
std::vector<bool> hot_frames(const std::vector<FrameEnergy>& f) {
  std::vector<double> mean;
  for (const FrameEnergy& x : f) mean.push_back(x.mean());
  const double med = mean.empty() ? 0 : median(mean);
  std::vector<bool> hot;
  for (double x : mean) hot.push_back(x > 4 * med);
  return hot;
}

// Share of the residual energy in the hot frames, times how contiguous they are in time (hot
// frames over the frames of their span): a clock that jumps heats every frame after it, a gyro
// that clips only the fast frames of each swing, scattered over the recording.
Located time_signal(const std::vector<FrameEnergy>& f, const std::vector<bool>& hot) {
  double total = 0, heat = 0;
  int first = -1, last = -1, n_hot = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    total += f[k].sum;
    if (hot[k]) heat += f[k].sum, last = static_cast<int>(k), first = first < 0 ? last : first, ++n_hot;
  }
  if (first < 0 || total <= 0) return {"time", 0, ""};
  std::ostringstream d;
  d << "residual concentrated in frames " << f[first].rank << " to " << f[last].rank << " (time order)";
  return {"time", heat / total * n_hot / (last - first + 1), d.str()};
}

// The largest rate about one gyro axis (rad/s, the gyro's own axes) between a and b on the
// motion clock: a gyro clips each axis at its range.
double peak_axis_rate(const std::vector<GyroSample>& g, double a, double b) {
  auto it = std::lower_bound(g.begin(), g.end(), a, [](const GyroSample& s, double t) { return s.t < t; });
  double peak = 0;
  for (; it != g.end() && it->t <= b; ++it) peak = std::max(peak, it->w.cwiseAbs().maxCoeff());
  return peak;
}

// Share of the residual energy in the hot frames, times how purely they are the frames of the
// fastest rotation (hot frames over the frames at least as fast as the slowest tenth of them):
// a gyro that clips, or blur, leaves the slow frames alone.
Located rate_signal(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx, const Patterns& s,
                    const std::vector<FrameEnergy>& f, const std::vector<bool>& hot) {
  std::vector<double> rate_of_rank;
  const double offset = p[Param::TimeOffset], period = 1.0 / m.recording().nominal.frame_rate_hz;
  for (int k : s.keep) {
    const int i = idx[k], rank = m.frame_rank(i);
    if (rank >= static_cast<int>(rate_of_rank.size())) rate_of_rank.resize(rank + 1, -1);
    if (rate_of_rank[rank] < 0)
      rate_of_rank[rank] = peak_axis_rate(m.recording().gyro, std::min(m.frame_time(i), m.frame_time_b(i)) + offset,
                                          std::max(m.frame_time(i), m.frame_time_b(i)) + period + offset);
  }
  std::vector<double> hot_rates;
  double total = 0, heat = 0;
  for (size_t k = 0; k < f.size(); ++k) {
    total += f[k].sum;
    if (hot[k]) heat += f[k].sum, hot_rates.push_back(rate_of_rank[f[k].rank]);
  }
  if (hot_rates.empty() || total <= 0) return {"fast_rotation", 0, ""};
  std::sort(hot_rates.begin(), hot_rates.end());
  const double slow_hot = hot_rates[hot_rates.size() / 10];
  int as_fast = 0;
  for (const FrameEnergy& x : f) as_fast += rate_of_rank[x.rank] >= slow_hot ? 1 : 0;
  std::ostringstream d;
  d << "residual concentrated in the frames of fastest rotation (from " << slow_hot
    << " rad/s about one gyro axis): a gyro that clips there, or blur";
  return {"fast_rotation", heat / total * static_cast<double>(hot_rates.size()) / std::max(1, as_fast), d.str()};
}

}  // namespace

std::vector<Located> locate(const DiagnosisModel& m, const ModelParams& p, const std::vector<int>& idx_all) {
  const std::vector<int> idx = subsample(idx_all, 3000);
  const auto base = m.residuals(p, idx);
  const Patterns s = inlier_patterns(m, base, idx);
  if (s.r.size() < 8) return {};
  const bool matches = m.kind() == ObservationKind::Matches;
  std::vector<Param> params = {Param::TimeOffset, Param::LineDelay, Param::K1, Param::K2, Param::Fx, Param::Fy, Param::Drift};
  // Columns 7-9: the gyro bias (gyro recordings) or the lever arm (trajectories).
  if (m.has_gyro()) params.insert(params.end(), {Param::BiasX, Param::BiasY, Param::BiasZ});
  else params.insert(params.end(), {Param::LeverX, Param::LeverY, Param::LeverZ});
  const Eigen::MatrixXd A = derivatives(m, p, idx, base, s, params);
  const std::vector<FrameEnergy> frames = frame_energies(s.frame_energy);
  const std::vector<bool> hot = hot_frames(frames);
  // A time shift and a row delay both move points along their image motion; each signal's
  // strength is what it explains beyond the other, so the two do not claim the same energy.
  const double both = explained(columns(A, {0, 1}), s.r);
  std::vector<Located> out = {
      {"image_velocity", std::max(0.0, both - explained(columns(A, {1}), s.r)),
       matches ? "residual follows the change of the image motion over the frame interval (angular "
                 "acceleration), the same for all rows: a time shift"
               : "residual follows the image motion, the same for all rows: a time shift"},
      {"row", std::max(0.0, both - explained(columns(A, {0}), s.r)),
       "residual along the image motion grows linearly with image row: row timing"},
      {"radius", explained(columns(A, {2, 3}), s.r), "residual radial, growing with r^2 and r^4: lens distortion"},
      {"image_scale", explained(columns(A, {4, 5}), s.r),
       "residual proportional to distance from the principal point: scale"},
      {"time_trend", std::max(0.0, explained(columns(A, {0, 6}), s.r) - explained(columns(A, {0}), s.r)),
       "the time shift grows linearly over the recording: clock rate"},
      time_signal(frames, hot)};
  if (m.has_gyro()) out.push_back(rate_signal(m, p, idx, s, frames, hot));
  Eigen::MatrixXd timing(A.rows(), 3);
  timing << columns(A, {0, 1}), column_pattern(m, idx, s, A);
  out.push_back({"column", std::max(0.0, explained(timing, s.r) - both),
                 "residual along the image motion grows with image column: columns read at different times"});
  if (m.has_gyro())
    out.push_back({"angular_rate", explained(columns(A, {7, 8, 9}), s.r),
                   "residual is the image motion of a constant angular-rate error: gyro rate"});
  else
    out.push_back({"depth", explained(columns(A, {7, 8, 9}), s.r),
                   "residual is a shift that shrinks with the point's depth: the camera sits off the tracked origin"});
  // Signals explaining under 5% of the residual are noise-level coincidences.
  out.erase(std::remove_if(out.begin(), out.end(), [](const Located& l) { return l.strength < 0.05; }), out.end());
  std::sort(out.begin(), out.end(), [](const Located& a, const Located& b) { return a.strength > b.strength; });
  return out;
}

}  // namespace rsd::dsp
